#!/usr/bin/env bash
# Runs the main job: prepares the environment (as ./test.sh does), then the default demo (the
# harbour tug towing the seed 002 barge), writing output/default_demo.mcap. Extra arguments go
# to run_scenario, e.g. ./run.sh --duration 30
set -o pipefail
cd "$(dirname "${BASH_SOURCE[0]}")" || exit 1
source scripts/ensure_env.sh || exit 1
exec ros2 run scenario_runner run_scenario default_demo.yaml "$@"
