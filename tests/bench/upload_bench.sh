#!/usr/bin/env bash
# Upload throughput of a mission through `keel submit` on loopback, as a ratio to writing the
# same bytes to the same disk with dd (issue 2's target: >= 0.5).
#   bash tests/bench/upload_bench.sh [size_mib] [build_dir]     (default 1024 MiB, ./build)
set -euo pipefail
size_mib="${1:-1024}"
build="$(cd "${2:-$(dirname "$0")/../../build}" && pwd)"
work="$(mktemp -d "${TMPDIR:-/tmp}/keel-upload-bench-XXXXXX")"
trap 'kill -TERM $server 2>/dev/null || true; wait 2>/dev/null; rm -rf "$work"' EXIT

mkdir -p "$work/mission" "$work/data"
printf 'keel_mission: 1\nname: upload-bench\nsensors:\n  - {name: imu, type: imu, file: imu.csv, rate_hz: 200}\n' \
  >"$work/mission/mission.yaml"
printf 't,wx,wy,wz,ax,ay,az\n0,0,0,0,0,0,9.81\n' >"$work/mission/imu.csv"
head -c "$((size_mib << 20))" /dev/urandom >"$work/mission/payload.bin"
sync

seconds() { date +%s.%N; }
rate() { awk -v b="$1" -v t="$2" 'BEGIN { printf "%.1f", b / t / 1048576 }'; }

t0=$(seconds)
dd if="$work/mission/payload.bin" of="$work/data/dd.bin" bs=16M conv=fsync status=none
t1=$(seconds)
dd_s=$(awk -v a="$t0" -v b="$t1" 'BEGIN { print b - a }')
rm -f "$work/data/dd.bin"

"$build/bin/keel-server" --data-dir "$work/data" --listen 127.0.0.1:0 --workers 0 >"$work/server.log" 2>&1 &
server=$!
for _ in $(seq 1 100); do [ -s "$work/data/server.url" ] && break; sleep 0.1; done
export KEEL_URL="$(cat "$work/data/server.url")" KEEL_TOKEN_FILE="$work/data/token"

t0=$(seconds)
"$build/bin/keel" submit "$work/mission" --stages ingest --cache-dir "$work/cache" -q >/dev/null
t1=$(seconds)
submit_s=$(awk -v a="$t0" -v b="$t1" 'BEGIN { print b - a }')

bytes=$((size_mib << 20))
echo "payload:                 $size_mib MiB"
echo "dd (bs=16M conv=fsync):  ${dd_s} s  $(rate $bytes "$dd_s") MiB/s"
echo "keel submit (tar+hash+upload+mission+job): ${submit_s} s  $(rate $bytes "$submit_s") MiB/s"
awk -v d="$dd_s" -v s="$submit_s" 'BEGIN { printf "ratio keel submit / dd:  %.2f (target >= 0.5)\n", d / s }'
