#!/usr/bin/env bash
# The README's demo: install packages, build, start keel-server with local workers, simulate
# a mission with keel-sim, submit it with `keel`, wait, and fetch every artifact.
#   bash deploy/demo.sh [output-folder]        (default: ./demo-out)
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
out="$(mkdir -p "${1:-$here/demo-out}" && cd "${1:-$here/demo-out}" && pwd)"
build="${KEEL_BUILD_DIR:-$here/build}"
scenario="${KEEL_DEMO_SCENARIO:-usv-bridge}"
duration="${KEEL_DEMO_DURATION:-60}"
# A hull mission has no lidar or sonar to map: its products are the BA and the inspection.
default_stages="ingest,refine,map"
[ "$scenario" = hauv-hull ] && default_stages="ingest,refine,ba,inspect"
stages="${KEEL_DEMO_STAGES:-$default_stages}"

bash "$here/deploy/setup.sh"
# Paths relative to the checkout, so a fresh clone elsewhere hits the same ccache entries.
export CCACHE_BASEDIR="$here"
cmake -G Ninja -S "$here" -B "$build" -DCMAKE_BUILD_TYPE=Release >/dev/null
ninja -C "$build" keel-server keel-worker keel keel-sim

server_bin="$build/bin/keel-server"
keel_bin="$build/bin/keel"
sim_bin="$build/bin/keel-sim"
data="$out/server-data"
rm -rf "$data" "$out/mission" "$out/artifacts"
mkdir -p "$data"

echo "== starting keel-server with 2 workers (data in $data)"
"$server_bin" --data-dir "$data" --listen 127.0.0.1:0 --workers 2 >"$out/server.log" 2>&1 &
server_pid=$!
trap 'kill -TERM $server_pid 2>/dev/null; wait $server_pid 2>/dev/null || true' EXIT
for _ in $(seq 1 100); do
  [ -s "$data/server.url" ] && [ -s "$data/token" ] && break
  sleep 0.1
done
[ -s "$data/server.url" ] || { echo "keel-server did not start; see $out/server.log"; exit 1; }
export KEEL_URL="$(cat "$data/server.url")"
export KEEL_TOKEN_FILE="$data/token"
echo "   listening on $KEEL_URL"
echo "   web dashboard: $KEEL_URL/  (sign in with the API token in $KEEL_TOKEN_FILE)"

if [ "$scenario" = hauv-hull ] && [ "$duration" != 0 ]; then
  echo "   (a $duration s hull mission surveys part of the first lane; KEEL_DEMO_DURATION=0 flies"
  echo "    the whole survey, ~240 s of mission, past every foreign object)"
fi
echo "== simulating a $scenario mission ($duration s; 0 = the whole path)"
"$sim_bin" --scenario "$scenario" --seed 1 --duration "$duration" --out "$out/mission"

echo "== submitting with keel (stages: $stages)"
job="$("$keel_bin" submit "$out/mission" --stages "$stages" --cache-dir "$out/.keel-cache")"
echo "   job $job"
"$keel_bin" watch "$job"

echo "== fetching artifacts"
"$keel_bin" fetch "$job" -o "$out/artifacts"
ls -l "$out/artifacts"
/usr/bin/python3 "$here/deploy/demo_summary.py" "$out/artifacts/report.json"
echo "== done: artifacts in $out/artifacts, report at $out/artifacts/report.json"
echo "   the same figures as one self-contained page: $out/artifacts/report.html"
echo "   web dashboard of this job: $KEEL_URL/#/jobs/$job  (report: #/jobs/$job/report, 3D: #/jobs/$job/viewer)"
echo "   sign in with the token in $KEEL_TOKEN_FILE"
# On a terminal the server stays up for the dashboard until Ctrl-C (KEEL_DEMO_SERVE=0: exit now).
if [ -t 0 ] && [ "${KEEL_DEMO_SERVE:-1}" != 0 ]; then
  echo "   the server keeps running for the dashboard; press Ctrl-C to stop it"
  wait "$server_pid" || true
fi
