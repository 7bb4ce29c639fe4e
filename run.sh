#!/usr/bin/env bash
# Runs the main job: prepares the environment (as ./test.sh does), then the default demo.
# Extra arguments go to the runner.
set -o pipefail
cd "$(dirname "${BASH_SOURCE[0]}")" || exit 1
source scripts/ensure_env.sh || exit 1
exec python -m scenario_runner.demo "$@"
