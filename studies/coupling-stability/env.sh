# source me from this folder: PYTHONPATH for the ROS-free packages of this clone
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
S=$ROOT/ros_ws/src
export PYTHONPATH=$S/rope_model:$S/tug_dynamics:$S/sim_math:$S/sim_contract:$S/sea_environment:$S/hull_contact:$ROOT/studies/coupling-stability
export PY=$ROOT/.venv/bin/python
export NUMBA_CACHE_DIR=/tmp/tugsim-coupling-study-numba
export PYTHONDONTWRITEBYTECODE=1
