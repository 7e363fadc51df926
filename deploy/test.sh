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

# The ROS 2 bag parsers under libFuzzer (clang, ASan + UBSan), KEEL_FUZZ_SECONDS (30) each,
# in a build of their own (tests/fuzz/CMakeLists.txt). KEEL_SKIP_FUZZ=1 leaves them out.
if [ "${KEEL_SKIP_FUZZ:-0}" != 1 ]; then
  cmake -G Ninja -S "$here" -B "$build-fuzz" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DKEEL_FUZZ=ON \
    -DKEEL_FUZZ_SECONDS="${KEEL_FUZZ_SECONDS:-30}" >/dev/null
  ninja -C "$build-fuzz" -j "$(nproc)" keel_fuzzers
  ctest --test-dir "$build-fuzz" -L fuzz --output-on-failure
fi
