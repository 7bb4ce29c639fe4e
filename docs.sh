#!/usr/bin/env bash
# The documentation site (MkDocs Material: mkdocs.yml, docs/). Prepares the environment first,
# like ./run.sh and ./test.sh, then:
#   ./docs.sh                  serves it on http://127.0.0.1:8000, reloading on every edit
#   ./docs.sh build            checks that the generated scenario reference is current, then builds
#                              the site with --strict (any warning fails) into site/
# Extra arguments go to mkdocs, e.g. ./docs.sh -a 0.0.0.0:8000 or ./docs.sh build --site-dir /tmp/site
set -o pipefail
cd "$(dirname "${BASH_SOURCE[0]}")" || exit 1
source scripts/ensure_env.sh || exit 1
if [ "${1:-}" = build ]; then
    shift
    python scripts/gen_docs.py --check >/dev/null || exit 1
    exec mkdocs build --strict "$@"
fi
exec mkdocs serve "$@"
