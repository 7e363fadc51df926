#!/usr/bin/env bash
# Runs node with the given arguments, or exits 77 (CTest: skipped) saying what is missing.
set -euo pipefail
here="$(cd "$(dirname "$0")/../.." && pwd)"
command -v node >/dev/null || { echo "SKIP: no node on PATH (deploy/setup.sh installs nodejs)"; exit 77; }
[ -d "$here/web/node_modules/three" ] || { echo "SKIP: web/node_modules is missing (deploy/setup.sh runs npm ci in web/)"; exit 77; }
exec node "$@"
