#!/usr/bin/env bash
# Runs one libFuzzer harness until it has used CPU_SECONDS of CPU time (utime + stime, read
# from /proc every 10 s), then stops it with SIGINT; libFuzzer prints its final stats. Wall
# time would under-count a harness that shares its cores with other work (issue 15's hour of
# fuzzing per harness is an hour of a core).
#   bash tests/fuzz/run_for_cpu.sh HARNESS CORPUS_DIR [CPU_SECONDS=3600] [LOG]
# Build the harnesses first (build-fuzz, see README). Exit status: libFuzzer's (72 when stopped
# at the budget, 1 and a crash-* file in the current folder when it found a crash).
set -uo pipefail
here="$(cd "$(dirname "$0")/../.." && pwd)"
harness="${1:?usage: run_for_cpu.sh HARNESS CORPUS_DIR [CPU_SECONDS] [LOG]}"
corpus="${2:?usage: run_for_cpu.sh HARNESS CORPUS_DIR [CPU_SECONDS] [LOG]}"
budget="${3:-3600}"
log="${4:-fuzz_$harness.log}"
binary="${KEEL_FUZZ_BUILD_DIR:-$here/build-fuzz}/tests/fuzz/fuzz_$harness"
[ -x "$binary" ] || { echo "no $binary: build it with ninja -C build-fuzz fuzz_$harness" >&2; exit 2; }
"$binary" -max_total_time=$((budget * 20)) -rss_limit_mb=2048 -timeout=10 -print_final_stats=1 \
  "$corpus" >"$log" 2>&1 &
pid=$!
ticks=$(getconf CLK_TCK)
utime=0 stime=0
while kill -0 "$pid" 2>/dev/null; do
  read -r utime stime < <(awk '{print $14, $15}' "/proc/$pid/stat" 2>/dev/null || echo "0 0")
  if [ $(((utime + stime) / ticks)) -ge "$budget" ]; then kill -INT "$pid"; break; fi
  sleep 10
done
wait "$pid"
status=$?
grep -E "stat::number_of_executed_units|stat::peak_rss_mb" "$log"
echo "fuzz_$harness: exit $status after $(((utime + stime) / ticks)) CPU-s; log $log"
exit $status
