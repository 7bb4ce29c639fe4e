#!/usr/bin/env bash
# Runs the whole test suite: prepares the environment (venv from requirements.lock, ROS 2
# Jazzy wheels, colcon build; skipped when nothing changed), then pytest. Extra arguments go
# to pytest, e.g. ./test.sh tests/physics -k rope
set -o pipefail
cd "$(dirname "${BASH_SOURCE[0]}")" || exit 1
source scripts/ensure_env.sh || exit 1
exec python -m pytest "$@"
