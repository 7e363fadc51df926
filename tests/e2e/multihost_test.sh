#!/usr/bin/env bash
# Keel on several hosts, made on one machine with network namespaces joined by a bridge in
# a namespace of its own: "db" (PostgreSQL; the blob folder is a path every host sees, as
# NFS would be), replicas "a" and "b" (keel-server --database), "lb" (nginx with
# deploy/nginx/keel.conf in front of both) and workers "w1".."w3" (keel-worker via nginx,
# 4 s leases). 20 missions are submitted through replica a and watched through replica b.
# Mid-run: replica a is killed -9, worker w1 is killed -9 while it holds a job, and w2's link
# is cut (ip link set down) for 3 lease times, then restored. Every job must end succeeded
# once (one report.json artifact per job, no job failed), every artifact downloaded through
# b must match its SHA-256, and every blob file in the shared folder must hash to its name.
# Where namespaces cannot be made, the same runs on loopback ports (the link cut becomes a
# SIGSTOP of w2 for as long), saying so.
#   tests/e2e/multihost_test.sh BIN_DIR SOURCE_DIR
set -euo pipefail
bin="$1" src="$2"
pgbin="$(ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V | tail -1)"
[ -x "$pgbin/initdb" ] || { echo "PostgreSQL not installed: skipped"; exit 77; }
nginx="$(command -v nginx || echo /usr/sbin/nginx)"
[ -x "$nginx" ] || { echo "nginx not installed: skipped"; exit 77; }
[ "$(id -u)" -eq 0 ] || { echo "needs root (initdb as postgres, namespaces): skipped"; exit 77; }

id=$$
tmp="$(mktemp -d /tmp/keel-multihost-XXXXXX)"
chmod 755 "$tmp"
declare -A pid_of
mode=netns
net="10.$((100 + id % 100)).$((id / 100 % 250)).0"; net="${net%.0}"
cleanup() {
  set +e
  for p in "${pid_of[@]}"; do kill -9 "$p" 2>/dev/null; done
  [ -f "$tmp/nginx.pid" ] && kill "$(cat "$tmp/nginx.pid")" 2>/dev/null
  runuser -u postgres -- "$pgbin/pg_ctl" -D "$tmp/pg" -m immediate stop >/dev/null 2>&1
  if [ -n "${made_netns:-}" ]; then
    for h in sw db a b lb w1 w2 w3; do ip netns del "k$id-$h" 2>/dev/null; done
    ip link del "v${id}r" 2>/dev/null
  fi
  sleep 0.5
  [ -n "${KEEP:-}" ] || rm -rf "$tmp"
}
trap cleanup EXIT
trap 'exit 1' TERM INT
fail() {
  echo "FAILED: $*"
  for f in "$tmp"/*.log "$tmp"/pgrun/*.log; do echo "== $f"; tail -15 "$f"; done
  exit 1
}

# --- hosts ---
if ip netns add "k$id-sw" 2>/dev/null; then
  made_netns=1
  ip -n "k$id-sw" link add br0 type bridge && ip -n "k$id-sw" link set br0 up
  ip -n "k$id-sw" link set lo up
  # The test itself (this namespace) joins the bridge as $net.254.
  ip link add "v${id}r" type veth peer name "p${id}r"
  ip link set "p${id}r" netns "k$id-sw"
  ip -n "k$id-sw" link set "p${id}r" master br0 up
  ip addr add "$net.254/24" dev "v${id}r" && ip link set "v${id}r" up
  n=1
  for h in db a b lb w1 w2 w3; do
    ip netns add "k$id-$h"
    ip link add "e$id$h" type veth peer name "p$id$h"
    ip link set "e$id$h" netns "k$id-$h"
    ip link set "p$id$h" netns "k$id-sw"
    ip -n "k$id-sw" link set "p$id$h" master br0 up
    ip -n "k$id-$h" link set lo up
    ip -n "k$id-$h" addr add "$net.$n/24" dev "e$id$h"
    ip -n "k$id-$h" link set "e$id$h" up
    declare "addr_${h}=$net.$n"
    n=$((n + 1))
  done
else
  mode=loopback
fi
if [ "$mode" = loopback ]; then
  echo "network namespaces cannot be made here: running on loopback ports instead"
  for h in db a b lb w1 w2 w3; do declare "addr_${h}=127.0.0.1"; done
fi
on() {  # host, command...
  local host="$1"; shift
  if [ "$mode" = netns ]; then ip netns exec "k$id-$host" "$@"; else "$@"; fi
}
# Backgrounded as `on_exec host cmd... &`: the subshell becomes the program itself (exec; so
# does ip netns exec), so $! is the program's pid and kill -9 reaches it.
on_exec() {
  local host="$1"; shift
  if [ "$mode" = netns ]; then exec ip netns exec "k$id-$host" "$@"; else exec "$@"; fi
}
free_port() { /usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])'; }
if [ "$mode" = netns ]; then port_db=5432 port_a=8080 port_b=8080 port_lb=8080
else port_db=$(free_port) port_a=$(free_port) port_b=$(free_port) port_lb=$(free_port); fi
echo "hosts ($mode): db $addr_db, replicas $addr_a:$port_a $addr_b:$port_b, nginx $addr_lb:$port_lb"

# --- PostgreSQL on host db ---
mkdir -p "$tmp/pg" "$tmp/pgrun" && chown postgres "$tmp/pg" "$tmp/pgrun"
runuser -u postgres -- "$pgbin/initdb" -D "$tmp/pg" -A trust -U postgres >"$tmp/initdb.log" 2>&1 ||
  fail "initdb"
echo "host all all 0.0.0.0/0 trust" >>"$tmp/pg/pg_hba.conf"
on db runuser -u postgres -- "$pgbin/pg_ctl" -D "$tmp/pg" -l "$tmp/pgrun/postgres.log" -w \
  -o "-p $port_db -k $tmp/pgrun -c listen_addresses=$addr_db -c fsync=off" start >/dev/null ||
  fail "pg_ctl start"
runuser -u postgres -- psql -q -h "$tmp/pgrun" -p "$port_db" -U postgres -c "CREATE DATABASE keel" ||
  fail "createdb"
# From this host over the network: the hosts reach each other.
psql -q -h "$addr_db" -p "$port_db" -U postgres -d keel -c "SELECT 1" >/dev/null ||
  fail "PostgreSQL on host db cannot be reached at $addr_db:$port_db"
db_url="postgresql://postgres@$addr_db:$port_db/keel"

# --- two replicas, one blob folder ---
start_replica() {  # name
  local address="addr_$1" port="port_$1"
  on_exec "$1" "$bin/keel-server" --data-dir "$tmp/$1" --listen "${!address}:${!port}" --workers 0 \
    --database "$db_url" --blob-dir "$tmp/blobs" --requeue-seconds 1 >>"$tmp/server-$1.log" 2>&1 &
  pid_of[$1]=$!
  for _ in $(seq 300); do [ -s "$tmp/$1/server.url" ] && return 0; sleep 0.1; done
  fail "replica $1 did not start"
}
start_replica a
start_replica b
token="$(cat "$tmp/a/token")"

# --- nginx on host lb, deploy/nginx/keel.conf with these replicas ---
sed -e "/server 10.0.0.11:8080/c\    server $addr_a:$port_a max_fails=1 fail_timeout=5s;" \
    -e "/server 10.0.0.12:8080/c\    server $addr_b:$port_b max_fails=1 fail_timeout=5s;" \
    -e "s/listen 80;/listen $addr_lb:$port_lb;/" \
    "$src/deploy/nginx/keel.conf" >"$tmp/keel.conf"
cat >"$tmp/nginx.conf" <<CONF
pid $tmp/nginx.pid;
error_log $tmp/nginx.log;
events {}
http { access_log off; client_body_temp_path $tmp/nginx-body; proxy_temp_path $tmp/nginx-proxy; include $tmp/keel.conf; }
CONF
on lb "$nginx" -p "$tmp" -c "$tmp/nginx.conf" || fail "nginx"
lb_url="http://$addr_lb:$port_lb"

# --- three workers through nginx ---
start_worker() {  # name
  on_exec "$1" "$bin/keel-worker" serve --server "$lb_url" --token-file "$tmp/a/token" \
    --cache-dir "$tmp/cache-$1" --name "$1" --lease-seconds 4 --heartbeat-seconds 0.5 \
    --wait-seconds 5 --request-timeout 10 >>"$tmp/worker-$1.log" 2>&1 &
  pid_of[$1]=$!
}
# --- 20 missions through replica a ---
api() {  # replica url, path
  curl -sf --max-time 10 -H "Authorization: Bearer $token" "$1$2"
}
url_a="http://$addr_a:$port_a" url_b="http://$addr_b:$port_b"
mission() {  # name: a lidar of 15,000 scans (ingest reads them one by one: seconds)
  local dir="$tmp/missions/$1"
  mkdir -p "$dir/lidar"
  printf 'keel_mission: 1\nname: %s\nplatform: usv\nsensors:\n  - name: lidar\n    type: lidar\n    scans: lidar\n    rate_hz: 10\n' "$1" >"$dir/mission.yaml"
  printf '# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1\nDATA ascii\n0 0 1\n' >"$dir/lidar/s.pcd"
  { echo "t,file"; awk -v seed="$2" 'BEGIN { for (i = 0; i < 15000 + seed; ++i) printf "%d.%d,s.pcd\n", 1700000000 + int(i / 10), i % 10 }'; } >"$dir/lidar/index.csv"
}
export HOME="$tmp" XDG_CACHE_HOME="$tmp/xdg-cache" XDG_CONFIG_HOME="$tmp/xdg-config"
for i in $(seq -w 1 20); do
  mission "survey-$i" "$i"
  KEEL_URL="$url_a" KEEL_TOKEN="$token" "$bin/keel" submit -q "$tmp/missions/survey-$i" \
    >>"$tmp/jobs.txt" 2>>"$tmp/submit.log" || fail "submit survey-$i through replica a"
done
[ "$(wc -l <"$tmp/jobs.txt")" -eq 20 ] || fail "20 jobs expected"
echo "20 missions submitted through replica a"
# Workers start once every job is queued: started earlier, they could finish the first jobs
# while the rest are still being uploaded, and w1 might hold nothing when the faults begin.
for w in w1 w2 w3; do start_worker "$w"; done

jobs_json() { api "$url_b" "/v1/jobs?limit=100"; }
holder_of() {  # worker name -> a job it runs now ("" = none), as replica b sees it
  jobs_json | /usr/bin/python3 -c "import json,sys; print(next((j['id'] for j in json.load(sys.stdin)['jobs'] if j['state']=='running' and j['worker']=='$1'), ''))"
}
wait_holding() {  # worker name
  for _ in $(seq 600); do job="$(holder_of "$1")"; [ -n "$job" ] && { echo "$job"; return 0; }; sleep 0.1; done
  return 1
}

# --- faults ---
job="$(wait_holding w1)" || fail "w1 never held a job"
kill -9 "${pid_of[a]}"; unset 'pid_of[a]'
echo "replica a killed -9"
kill -9 "${pid_of[w1]}"; unset 'pid_of[w1]'
echo "worker w1 killed -9 while holding $job"
job="$(wait_holding w2)" || fail "w2 never held a job"
if [ "$mode" = netns ]; then
  ip -n "k$id-w2" link set "e${id}w2" down
  echo "worker w2's link cut while holding $job"
else
  kill -STOP "${pid_of[w2]}"
  echo "worker w2 stopped (SIGSTOP) while holding $job"
fi
sleep 12  # 3 lease times
if [ "$mode" = netns ]; then
  ip -n "k$id-w2" link set "e${id}w2" up
else
  kill -CONT "${pid_of[w2]}"
fi
echo "w2 back after 12 s"

# --- every job succeeded once, watched through replica b ---
deadline=$((SECONDS + 300))
while :; do
  summary="$(jobs_json | /usr/bin/python3 -c 'import json,sys,collections; print(" ".join(f"{k}={v}" for k,v in sorted(collections.Counter(j["state"] for j in json.load(sys.stdin)["jobs"]).items())))')" || summary="?"
  [ "$summary" = "succeeded=20" ] && break
  echo "$summary" | grep -qE "failed|canceled" && fail "a job ended badly: $summary"
  [ "$SECONDS" -lt "$deadline" ] || fail "not all succeeded within 300 s: $summary"
  sleep 1
done
echo "all 20 jobs succeeded (seen through replica b)"
lost=$(jobs_json | /usr/bin/python3 -c 'import json,sys; print(sum(1 for j in json.load(sys.stdin)["jobs"] if j["attempts"] > 1))')
echo "jobs run more than once after a fault: $lost"
[ "$lost" -ge 2 ] || fail "the killed worker's and the cut worker's jobs should have been leased again"

while read -r job; do
  arts="$(api "$url_b" "/v1/jobs/$job/artifacts")" || fail "artifacts of $job"
  # An ingest job writes report.json and report.html, each once however often it was leased.
  names="$(echo "$arts" | /usr/bin/python3 -c 'import json,sys; print(" ".join(sorted(a["name"] for a in json.load(sys.stdin)["artifacts"])))')"
  [ "$names" = "report.html report.json" ] || fail "job $job has artifacts [$names], expected report.html and report.json once each"
  KEEL_URL="$url_b" KEEL_TOKEN="$token" "$bin/keel" fetch -q "$job" -o "$tmp/fetched/$job" >/dev/null ||
    fail "fetch of $job through b (SHA-256 checked)"
  while read -r name expected; do
    got="$(sha256sum "$tmp/fetched/$job/$name" | cut -d' ' -f1)"
    [ "$got" = "$expected" ] || fail "$name of $job: sha256 $got, recorded $expected"
  done < <(echo "$arts" | /usr/bin/python3 -c 'import json,sys; [print(a["name"], a["sha256"]) for a in json.load(sys.stdin)["artifacts"]]')
done <"$tmp/jobs.txt"
echo "every job has one report.json and one report.html whose SHA-256 match"
bad=0
while read -r file; do
  [ "$(sha256sum "$file" | cut -d' ' -f1)" = "$(basename "$file")" ] || { echo "blob $file"; bad=$((bad + 1)); }
done < <(find "$tmp/blobs/blobs" -type f)
[ "$bad" -eq 0 ] || fail "$bad blob files do not hash to their names"
echo "every blob in the shared folder hashes to its name"
grep -qiE "abandoned|lease lost|lease_lost" "$tmp/worker-w2.log" ||
  fail "w2 came back without learning that its lease was lost"
echo "w2's stale lease was refused when its link came back"
echo "multihost ($mode): 5 passed, 0 failed"
