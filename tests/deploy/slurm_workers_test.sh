#!/usr/bin/env bash
# deploy/slurm/keel-workers.sbatch on a real single-node Slurm (slurmctld, slurmd, munged
# started here on private ports and folders; no system service): a job array of workers
# processes a reprocessing batch of 10 missions, each job succeeds on its first lease, and
# the workers leave once idle; then `scancel --signal=TERM --full` of an array whose workers hold long jobs queues
# those jobs again at once (release on SIGTERM), long before their 600 s leases expire.
# Exit 77 = skipped (Slurm or munge not installed, not root).
#   tests/deploy/slurm_workers_test.sh SOURCE_DIR BIN_DIR [batch-only]
set -euo pipefail
src="$1" bin="$2"
for tool in slurmctld slurmd munged sbatch scancel squeue; do
  command -v "$tool" >/dev/null || { echo "$tool not installed (slurm-wlm, munge): skipped"; exit 77; }
done
[ "$(id -u)" -eq 0 ] || { echo "slurmd must run as root: skipped"; exit 77; }

tmp="$(mktemp -d /tmp/keel-slurm-XXXXXX)"
chmod 755 "$tmp"
pids=()
cleanup() {
  for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done
  [ -f "$tmp/munged.pid" ] && kill "$(cat "$tmp/munged.pid")" 2>/dev/null || true
  [ -f "$tmp/slurmctld.pid" ] && kill "$(cat "$tmp/slurmctld.pid")" 2>/dev/null || true
  [ -f "$tmp/slurmd.pid" ] && kill "$(cat "$tmp/slurmd.pid")" 2>/dev/null || true
  sleep 1
  [ -n "${KEEP:-}" ] || rm -rf "$tmp"
}
trap cleanup EXIT
trap 'exit 1' TERM INT
fail() { echo "FAILED: $*"; for f in "$tmp"/*.log "$tmp"/out/*.log; do [ -f "$f" ] && { echo "== $f"; tail -20 "$f"; }; done; exit 1; }
free_port() { /usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])'; }

# --- munge, private key and socket, as user munge ---
mkdir -p "$tmp/munge"
dd if=/dev/urandom of="$tmp/munge/munge.key" bs=1024 count=1 status=none
chown -R munge:munge "$tmp/munge"
chmod 711 "$tmp/munge"; chmod 400 "$tmp/munge/munge.key"
runuser -u munge -- munged --key-file="$tmp/munge/munge.key" --socket="$tmp/munge/socket" \
  --pid-file="$tmp/munge/munged.pid" --log-file="$tmp/munge/munged.log" \
  --seed-file="$tmp/munge/seed" || fail "munged did not start"
cp "$tmp/munge/munged.pid" "$tmp/munged.pid"

# --- slurm.conf: one node, no accounting, munge keys in the test folder ---
host="$(hostname -s)"
cpus="$(nproc)"
mkdir -p "$tmp/state" "$tmp/spool" "$tmp/out"
cat >"$tmp/slurm.conf" <<CONF
ClusterName=keeltest
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$(free_port)
SlurmdPort=$(free_port)
SlurmUser=root
AuthType=auth/munge
AuthInfo=socket=$tmp/munge/socket
CredType=cred/munge
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/slurmctld.log
SlurmdLogFile=$tmp/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
MpiDefault=none
SwitchType=switch/none
ReturnToService=2
KillWait=30
SchedulerType=sched/builtin
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=1000 State=UNKNOWN
PartitionName=keel Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$tmp/slurm.conf"
slurmctld -f "$SLURM_CONF" || fail "slurmctld did not start"
slurmd -f "$SLURM_CONF" || fail "slurmd did not start"
for _ in $(seq 100); do sinfo -h -o %T 2>/dev/null | grep -qE '^(idle|mixed)' && break; sleep 0.2; done
sinfo -h -o %T | grep -qE '^(idle|mixed)' || fail "the node did not come up: $(sinfo 2>&1)"
echo "slurm: node $host up with $cpus CPUs"

# --- keel-server (no local workers) and 10 stored missions ---
"$bin/keel-server" --data-dir "$tmp/keel" --listen 127.0.0.1:0 --workers 0 --requeue-seconds 1 \
  >"$tmp/server.log" 2>&1 &
pids+=($!)
for _ in $(seq 200); do [ -s "$tmp/keel/server.url" ] && [ -s "$tmp/keel/token" ] && break; sleep 0.1; done
export KEEL_URL="$(head -1 "$tmp/keel/server.url")" KEEL_TOKEN="$(cat "$tmp/keel/token")"
export HOME="$tmp" XDG_CACHE_HOME="$tmp/cache" XDG_CONFIG_HOME="$tmp/config"
keel() { "$bin/keel" "$@"; }
count_state() {  # jobs in state $1, from the API
  curl -sf -H "Authorization: Bearer $KEEL_TOKEN" "$KEEL_URL/v1/jobs?state=$1" |
    /usr/bin/python3 -c 'import json,sys; print(len(json.load(sys.stdin)["jobs"]))'
}
long_mission() {  # name: a lidar of 200,000 scans; ingest checks for a stop between scans
  mkdir -p "$tmp/missions/$1/lidar"
  printf 'keel_mission: 1\nname: %s\nplatform: usv\nsensors:\n  - name: lidar\n    type: lidar\n    scans: lidar\n    rate_hz: 10\n' "$1" >"$tmp/missions/$1/mission.yaml"
  printf '# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1\nDATA ascii\n0 0 1\n' >"$tmp/missions/$1/lidar/s.pcd"
  { echo "t,file"; awk 'BEGIN { for (i = 0; i < 200000; ++i) printf "%d.%d,s.pcd\n", 1700000000 + int(i / 10), i % 10 }'; } >"$tmp/missions/$1/lidar/index.csv"
}

mission() {  # name, imu rows
  mkdir -p "$tmp/missions/$1"
  printf 'keel_mission: 1\nname: %s\nplatform: usv\nsensors:\n  - name: imu\n    type: imu\n    file: imu.csv\n    rate_hz: 200\n' "$1" >"$tmp/missions/$1/mission.yaml"
  { echo "t,wx,wy,wz,ax,ay,az"; awk -v n="$2" 'BEGIN { for (i = 0; i < n; ++i) printf "%.3f,0,0,0.1,0,0,9.81\n", 1700000000 + i / 200 }'; } >"$tmp/missions/$1/imu.csv"
}
for i in $(seq -w 1 10); do
  mission "survey-$i" 2000
  job="$(keel submit -q "$tmp/missions/survey-$i")" || fail "submit survey-$i"
  keel cancel "$job" >/dev/null
done
keel reprocess --prefix survey- --stages ingest >"$tmp/batch-jobs.txt" 2>"$tmp/batch.txt" || fail "reprocess"
batch="$(grep -o 'b_[0-9a-f]*' "$tmp/batch.txt" | head -1)"
[ "$(wc -l <"$tmp/batch-jobs.txt")" -eq 10 ] || fail "reprocess made $(wc -l <"$tmp/batch-jobs.txt") jobs"
echo "batch $batch of 10 jobs queued"

# --- the array processes the batch and leaves when idle ---
export KEEL_SERVER_URL="$KEEL_URL" KEEL_TOKEN_FILE="$tmp/keel/token" KEEL_WORKER="$bin/keel-worker"
export KEEL_IDLE_SECONDS=5
cd "$tmp/out"
array="$(sbatch --parsable --array=1-2 --cpus-per-task=1 --mem=100M "$src/deploy/slurm/keel-workers.sbatch")" ||
  fail "sbatch"
echo "sbatch: array $array"
timeout 150 "$bin/keel" jobs --batch "$batch" --follow --interval 1 >"$tmp/follow.log" || fail "a job of the batch failed: $(tail -3 "$tmp/follow.log")"
tail -2 "$tmp/follow.log"
grep -q "10 succeeded" "$tmp/follow.log" || fail "not 10 succeeded"
while read -r job; do
  attempts="$(keel status --json "$job" | /usr/bin/python3 -c 'import json,sys; print(json.load(sys.stdin)["attempts"])')"
  [ "$attempts" = 1 ] || fail "job $job took $attempts leases"
done <"$tmp/batch-jobs.txt"
echo "every job succeeded on its first lease"
for _ in $(seq 150); do [ -z "$(squeue -h -j "$array" 2>/dev/null)" ] && break; sleep 0.2; done
[ -z "$(squeue -h -j "$array")" ] || fail "workers still running after idle: $(squeue)"
grep -l "exit-when-idle" keel-worker-*.log >/dev/null || fail "no worker said it left when idle"
echo "the array's workers left after ${KEEL_IDLE_SECONDS} s idle"

if [ "${3:-}" = batch-only ]; then echo "slurm workers test (batch only): 1 passed, 0 failed"; exit 0; fi

# --- scancel: running jobs are queued again at once ---
long_mission long-a
long_mission long-b
for m in long-a long-b; do keel submit -q "$tmp/missions/$m" >>"$tmp/long-jobs.txt" || fail "submit $m"; done
export KEEL_WORKER_ARGS="--lease-seconds 600"
array="$(sbatch --parsable --array=1-2 --cpus-per-task=1 --mem=100M "$src/deploy/slurm/keel-workers.sbatch")"
for _ in $(seq 300); do
  [ "$(count_state running)" -ge 2 ] && break; sleep 0.2
done
[ "$(count_state running)" -ge 2 ] || fail "the long jobs did not start: $(keel jobs)"
start_ns=$(date +%s%N)
# Plain scancel kills at once (SIGKILL): the graceful stop signals TERM to every step
# including the batch shell and its children.
scancel --signal=TERM --full "$array"
queued=0
for _ in $(seq 300); do
  queued="$(count_state queued)"
  [ "$queued" -ge 2 ] && break; sleep 0.1
done
took_ms=$((($(date +%s%N) - start_ns) / 1000000))
[ "$queued" -ge 2 ] || fail "after scancel the jobs were not queued again: $(keel jobs)"
echo "scancel: both running jobs queued again after ${took_ms} ms (leases were 600 s)"
grep -h "lease given back" keel-worker-*.log | head -2
echo "slurm workers test: 2 passed, 0 failed"
