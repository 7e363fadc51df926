#!/usr/bin/env bash
# Builds the libFuzzer harnesses with clang (ASan + UBSan) and runs each for a bounded time.
#   bash tests/fuzz/run_fuzzers.sh SECONDS [harness...]
# Seeds: the regressions in tests/fuzz/regressions/<name>/, a mission written by keel-sim
# (when $KEEL_SIM is an executable; files sorted to the harness by extension) and the files
# in ../shared/data when present (up to 25 files of each kind from each), and the valid files
# fuzz_seeds writes: one of every encoding each reader accepts (tests/fuzz/file_seeds.h).
# Corpora grow in $KEEL_FUZZ_WORK (default build-fuzz/work).
# A crash stops with the harness's report and the input saved as crash-*; copy it into the
# regressions folder once fixed. Exit status: 0 when no harness crashed.
set -euo pipefail
here="$(cd "$(dirname "$0")/../.." && pwd)"
seconds="${1:?usage: run_fuzzers.sh SECONDS [harness...]}"
shift
build="${KEEL_FUZZ_BUILD_DIR:-$here/build-fuzz}"
work="${KEEL_FUZZ_WORK:-$build/work}"
all=(byte_range json_contracts bundle_check mission_yaml trajectory csv_streams scan_file bag mesh draco
  image a50 velodyne_packet gnss_csv init_messages)
if [ $# -gt 0 ]; then harnesses=("$@"); else harnesses=("${all[@]}"); fi

export CCACHE_BASEDIR="$here"
if [ ! -f "$build/build.ninja" ]; then
  cmake -G Ninja -S "$here" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DKEEL_FUZZ=ON \
    -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ >/dev/null
fi
ninja -C "$build" "${harnesses[@]/#/fuzz_}"

# Seeds by harness.
seeds="$work/seeds"
mkdir -p "$seeds"
if [ -n "${KEEL_SIM:-}" ] && [ -x "$KEEL_SIM" ] && [ ! -d "$seeds/mission" ]; then
  "$KEEL_SIM" --out "$seeds/mission" --duration 3 --bag >/dev/null 2>&1 || true
  "$KEEL_SIM" --scenario hauv-hull --out "$seeds/hull" --duration 3 >/dev/null 2>&1 || true
  (cd "$seeds/mission" && tar -cf "$seeds/mission.tar" mission.yaml) 2>/dev/null || true
fi
seeded_by_fuzz_seeds() {  # the harnesses fuzz_seeds writes a folder for
  case "$1" in draco | image | scan_file | mesh | trajectory | csv_streams | bundle_check | json_contracts | bag | a50) echo yes ;; esac
}
seed_files() {  # name -> files for it (prefixing the selector byte where the harness has one)
  local name="$1" dir="$work/corpus/$name"
  mkdir -p "$dir"
  [ -d "$here/tests/fuzz/regressions/$name" ] && cp -n "$here/tests/fuzz/regressions/$name"/* "$dir"/ 2>/dev/null || true
  # Valid files of every encoding from fuzz_seeds (CTest's fuzz/seeds writes them; made here
  # otherwise).
  if [ -n "$(seeded_by_fuzz_seeds "$name")" ]; then
    if [ ! -d "$build/fuzz-corpus/$name" ]; then
      ninja -C "$build" fuzz_seeds >/dev/null
      "$build/tests/fuzz/fuzz_seeds" "$build/fuzz-corpus" >/dev/null
    fi
    cp -n "$build/fuzz-corpus/$name"/* "$dir"/
  fi
  local patterns=()
  case "$name" in
    mission_yaml) patterns=("mission.yaml") ;;
    trajectory) patterns=("*.tum" "*.txt") ;;
    csv_streams) patterns=("*.csv") ;;
    scan_file) patterns=("*.pcd" "*.ply") ;;
    bag) patterns=("*.bag") ;;
    mesh) patterns=("*.ply" "*.obj" "*.stl" "*.off") ;;
    draco) patterns=("*.drc") ;;
    bundle_check) patterns=("*.tar") ;;
    *) patterns=() ;;
  esac
  local i=0 pattern source taken f
  for pattern in "${patterns[@]}"; do
    for source in "$seeds" "$here/../shared/data"; do
      taken=0
      while IFS= read -r -d '' f; do
        # Files over 1 MiB (keel-sim's bag, KCS.stl) would slow every input: fuzz_seeds writes
        # small whole ones (a ROS1 bag cut short is refused before a message is read).
        [ "$(stat -c %s "$f")" -le 1048576 ] || continue
        i=$((i + 1))
        if [ "$name" = mission_yaml ] || [ "$name" = bundle_check ] || [ "$name" = bag ]; then
          cp "$f" "$dir/seed-$i"
        else  # every selector value would be a different reader: seed each
          for s in 0 1 2 3 4 5; do { printf "\\x$s"; cat "$f"; } >"$dir/seed-$i-$s"; done
        fi
        taken=$((taken + 1))
        # keel-sim writes hundreds of scans of one encoding: a few of each source are enough
        [ $taken -ge 25 ] && break
      done < <(find "$source" -name "$pattern" -type f -print0 2>/dev/null | sort -z)
    done
  done
  echo "$dir"
}

failed=0
for name in "${harnesses[@]}"; do
  corpus="$(seed_files "$name")"
  log="$work/$name.log"
  echo "== fuzz_$name for ${seconds}s ($(ls "$corpus" | wc -l) inputs in its corpus)"
  if (cd "$work" && "$build/tests/fuzz/fuzz_$name" -max_total_time="$seconds" -rss_limit_mb=2048 \
        -timeout=10 -print_final_stats=1 "$corpus" >"$log" 2>&1); then
    grep -E "stat::number_of_executed_units|stat::peak_rss_mb" "$log" | tr '\n' ' '
    echo
  else
    failed=1
    echo "fuzz_$name FAILED: see $log"
    tail -50 "$log"
  fi
done
exit $failed
