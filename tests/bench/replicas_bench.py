#!/usr/bin/python3
"""Issue 14 targets through HTTP, on two keel-server replicas sharing a private PostgreSQL
(started here with initdb/pg_ctl) and one blob folder:
  1. wake-up: a worker's long-poll lease waits on replica B; a job is created on replica A;
     time from A's 201 to B's lease answer (target: <= 100 ms; NOTIFY, not a poll);
  2. reprocess: POST /v1/reprocess over M stored missions on replica A (target: <= 2 s for
     10,000), the batch made in one transaction.
Run as root (initdb runs as postgres): /usr/bin/python3 tests/bench/replicas_bench.py BIN_DIR
  [--wakeups 30] [--missions 10000]"""
import argparse, json, os, pathlib, shutil, socket, statistics, subprocess, sys, tempfile, threading, time
import urllib.request

def free_port():
    s = socket.socket(); s.bind(("127.0.0.1", 0)); p = s.getsockname()[1]; s.close(); return p

def call(url, token, method, path, body=None, timeout=60):
    data = json.dumps(body).encode() if body is not None else None
    req = urllib.request.Request(url + path, data=data, method=method,
                                 headers={"Authorization": "Bearer " + token, "Content-Type": "application/json"})
    with urllib.request.urlopen(req, timeout=timeout) as r:
        raw = r.read()
        return r.status, (json.loads(raw) if raw else None)

def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("bin"); ap.add_argument("--wakeups", type=int, default=30)
    ap.add_argument("--missions", type=int, default=10000)
    args = ap.parse_args()
    pgbin = sorted(pathlib.Path("/usr/lib/postgresql").glob("*/bin"))[-1]
    tmp = pathlib.Path(tempfile.mkdtemp(prefix="keel-replicas-bench-")); os.chmod(tmp, 0o755)
    procs = []
    try:
        pg = tmp / "pg"; pg.mkdir(); shutil.chown(pg, "postgres")
        port = free_port()
        run_pg = lambda *a: subprocess.run(["runuser", "-u", "postgres", "--", *a], check=True, capture_output=True)
        run_pg(str(pgbin / "initdb"), "-D", str(pg), "-A", "trust", "-U", "postgres")
        run_pg(str(pgbin / "pg_ctl"), "-D", str(pg), "-l", str(pg / "log"), "-w", "-o",
               f"-p {port} -k {pg} -c listen_addresses=127.0.0.1", "start")
        run_pg("psql", "-q", "-h", str(pg), "-p", str(port), "-c", "CREATE DATABASE keel")
        url_db = f"postgresql://postgres@127.0.0.1:{port}/keel"
        urls = {}
        for name in ("a", "b"):
            (tmp / name).mkdir()
            log = open(tmp / f"{name}.log", "w")
            procs.append(subprocess.Popen([f"{args.bin}/keel-server", "--data-dir", str(tmp / name), "--listen",
                                           "127.0.0.1:0", "--workers", "0", "--database", url_db,
                                           "--blob-dir", str(tmp / "blobs"),
                                           # one token makes 10,000 missions as fast as it can
                                           "--rate-limit", "0"], stdout=log, stderr=log))
            for _ in range(300):
                if (tmp / name / "server.url").exists() and (tmp / name / "server.url").read_text().strip(): break
                time.sleep(0.1)
            urls[name] = (tmp / name / "server.url").read_text().strip()
            if name == "a": time.sleep(0.5)
        token = (tmp / "a" / "token").read_text().strip()
        print(f"load average at start: {open('/proc/loadavg').read().split()[:3]} ({os.cpu_count()} cores)")

        # One stored mission through the CLI; its bundle blob is reused for the others.
        m = tmp / "mission"; m.mkdir()
        (m / "mission.yaml").write_text("keel_mission: 1\nname: survey-00000\nplatform: usv\nsensors:\n"
                                        "  - name: imu\n    type: imu\n    file: imu.csv\n    rate_hz: 200\n")
        (m / "imu.csv").write_text("t,wx,wy,wz,ax,ay,az\n0.0,0,0,0,0,0,9.81\n")
        env = dict(os.environ, KEEL_URL=urls["a"], KEEL_TOKEN=token, HOME=str(tmp), XDG_CACHE_HOME=str(tmp / "c"))
        job_id = subprocess.run([f"{args.bin}/keel", "submit", "-q", str(m)], env=env, check=True,
                                capture_output=True, text=True).stdout.strip()
        _, job = call(urls["a"], token, "GET", f"/v1/jobs/{job_id}")
        _, mission = call(urls["a"], token, "GET", f"/v1/missions/{job['mission_id']}")
        call(urls["a"], token, "POST", f"/v1/jobs/{job_id}/cancel", {})

        # 1. wake-up across replicas
        wakes = []
        for i in range(args.wakeups):
            answer = {}
            def wait_on_b():
                answer["status"], answer["body"] = call(urls["b"], token, "POST", "/v1/worker/lease",
                                                        {"worker": "bench", "lease_seconds": 30, "wait_seconds": 10})
                answer["t"] = time.monotonic()
            t = threading.Thread(target=wait_on_b); t.start()
            time.sleep(0.3)  # the lease call is waiting on B
            _, created = call(urls["a"], token, "POST", "/v1/jobs", {"mission_id": mission["id"], "stages": ["ingest"]})
            t_created = time.monotonic()
            t.join()
            if answer["status"] != 200 or answer["body"]["job"]["id"] != created["id"]:
                print(f"wake {i}: B answered {answer['status']} without the job"); continue
            wakes.append((answer["t"] - t_created) * 1000)
            lease = answer["body"]
            call(urls["b"], token, "POST", f"/v1/worker/jobs/{created['id']}/complete", {"lease_id": lease["lease_id"]})
        wakes.sort()
        print(f"wake-up, job created on A -> long-poll lease answered on B: median {statistics.median(wakes):.1f} ms, "
              f"p95 {wakes[int(0.95 * (len(wakes) - 1))]:.1f} ms, max {wakes[-1]:.1f} ms ({len(wakes)} of {args.wakeups})")

        # 2. reprocess over M stored missions
        t0 = time.monotonic()
        for i in range(1, args.missions):
            call(urls["a" if i % 2 else "b"], token, "POST", "/v1/missions",
                 {"name": f"survey-{i:05d}", "bundle_blob": mission["bundle_blob"]})
        print(f"{args.missions} missions stored in {time.monotonic() - t0:.1f} s")
        t0 = time.monotonic()
        status, body = call(urls["a"], token, "POST", "/v1/reprocess", {"name_prefix": "survey-", "stages": ["ingest"]}, timeout=120)
        took = time.monotonic() - t0
        print(f"POST /v1/reprocess over {body['batch']['jobs']} missions: {took * 1000:.0f} ms (status {status}, "
              f"{len(body['jobs'])} jobs listed in the answer)")
        print(f"load average at end: {open('/proc/loadavg').read().split()[:3]}")
    finally:
        for p in procs: p.terminate()
        for p in procs: p.wait(timeout=30)
        subprocess.run(["runuser", "-u", "postgres", "--", str(pgbin / "pg_ctl"), "-D", str(tmp / "pg"), "-m", "fast", "stop"],
                       capture_output=True)
        shutil.rmtree(tmp, ignore_errors=True)

main()
