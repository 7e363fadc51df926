#!/usr/bin/env bash
# The README's test command: install packages, build once (ccache), run every CTest test.
#   bash deploy/test.sh [extra ctest args]
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
build="${KEEL_BUILD_DIR:-$here/build}"

bash "$here/deploy/setup.sh"
# Paths relative to the checkout, so a fresh clone elsewhere hits the same ccache entries.
export CCACHE_BASEDIR="$here"
cmake -G Ninja -S "$here" -B "$build" -DCMAKE_BUILD_TYPE=Release >/dev/null
ninja -C "$build" -j "$(nproc)"
ctest --test-dir "$build" --output-on-failure -j "$(nproc)" "$@"
