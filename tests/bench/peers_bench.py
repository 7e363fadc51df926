#!/usr/bin/python3
"""Keel's `filter` and `metrics` against Open3D (Debian's python3-open3d) and CloudCompare
(Debian's cloudcompare, headless) on the same ~1 M-point map (issue 35). Run by hand, not a CTest
pass/fail; the output is meant to be pasted into docs/performance.md.

  /usr/bin/python3 tests/bench/peers_bench.py BIN_DIR [--runs 5] [--work DIR] [--copies 40]
      [--ror-runs N] [--only startup,voxel,ror,metrics]

The map: the real VLP-16 sweep ../shared/data/test_scan_vlp16.pcd (25,760 points) taken COPIES
times (default 40: 1,030,400 points); copy 0 is the sweep itself, copy k >= 1 is the sweep plus
independent Gaussian noise on every coordinate of every point, of sigma 0.02 m, or 0.5 m for the
points (2 % of each copy) that are to be strays for the outlier filter. numpy's
default_rng(35) draws, copy by copy, first which points stray (random() < 0.02), then the
standard normals (normal(0, 1, (n, 3))) that sigma scales. Stored as float32 x y z in a binary
little-endian PLY (12 MB) and a binary PCD.

Timings:
- process to process: a whole process that reads the file, does the work and writes its result,
  timed from outside (monotonic clock around start and reap); the two sides run in turn,
  A B A B ..., after one warm-up each, and the ratio is taken pair by pair; min / median / max.
- in memory: each side's own clock around the operation alone. Open3D: time.perf_counter in
  Python around the call. Keel: the "seconds" figures of `--json` (steady_clock around each
  filter and around the metrics computation). CloudCompare reports no per-command time: its
  figure is the median of its full run minus the median of the same run that only loads and
  saves (-O, -SAVE_CLOUDS), so it includes CloudCompare's octree build.
Only the standard library and numpy here; Open3D is imported only in the peer's own subprocess
(this file run with --open3d-side)."""
import argparse, json, os, pathlib, shutil, statistics, subprocess, sys, tempfile, time

HERE = pathlib.Path(__file__).resolve()
SCAN = HERE.parents[3] / "shared" / "data" / "test_scan_vlp16.pcd"
PY = "/usr/bin/python3"  # Debian's Python: python3-open3d and numpy
CC_ENV = dict(os.environ, QT_QPA_PLATFORM="offscreen")


# ---------------------------------------------------------------- the peer's own subprocess
def open3d_side(op, src, dst, a, b):
    t0 = time.perf_counter()
    import open3d as o3d
    t_import = time.perf_counter() - t0
    cloud = o3d.io.read_point_cloud(src)
    t0 = time.perf_counter()
    if op == "voxel":
        out = cloud.voxel_down_sample(voxel_size=float(a))
    elif op == "ror":
        out, _ = cloud.remove_radius_outlier(nb_points=int(b), radius=float(a))
    else:
        raise SystemExit("unknown op " + op)
    seconds = time.perf_counter() - t0
    o3d.io.write_point_cloud(dst, out, write_ascii=False)
    print(json.dumps({"points_in": len(cloud.points), "points_out": len(out.points),
                      "seconds": seconds, "import_seconds": t_import}))


# ---------------------------------------------------------------- the map
def read_ascii_pcd_xyz(path):
    import numpy as np
    lines = pathlib.Path(path).read_text().splitlines()
    fields = next(l for l in lines if l.startswith("FIELDS")).split()[1:]
    start = next(i for i, l in enumerate(lines) if l.startswith("DATA")) + 1
    data = np.loadtxt(lines[start:], dtype=np.float64, ndmin=2)
    return data[:, [fields.index(c) for c in "xyz"]].astype(np.float32)


def make_map(work, copies):
    import numpy as np
    sweep = read_ascii_pcd_xyz(SCAN)
    rng = np.random.default_rng(35)
    parts = [sweep]
    for _ in range(1, copies):
        sigma = np.where(rng.random((len(sweep), 1)) < 0.02, 0.5, 0.02)
        parts.append((sweep + sigma * rng.normal(0.0, 1.0, sweep.shape)).astype(np.float32))
    xyz = np.ascontiguousarray(np.concatenate(parts), dtype="<f4")
    n = len(xyz)
    ply = work / "map.ply"
    ply.write_bytes((f"ply\nformat binary_little_endian 1.0\nelement vertex {n}\nproperty float x\n"
                     f"property float y\nproperty float z\nend_header\n").encode() + xyz.tobytes())
    pcd = work / "map.pcd"
    pcd.write_bytes((f"# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\n"
                     f"SIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH {n}\nHEIGHT 1\n"
                     f"VIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA binary\n").encode() + xyz.tobytes())
    return xyz, ply, pcd


def read_binary_ply(path):
    """Vertex element of a binary little-endian PLY (scalar properties only) as a dict of arrays."""
    import numpy as np
    raw = pathlib.Path(path).read_bytes()
    end = raw.index(b"end_header\n") + len(b"end_header\n")
    types = {"float": "<f4", "float32": "<f4", "double": "<f8", "float64": "<f8", "uchar": "u1",
             "uint8": "u1", "char": "i1", "int8": "i1", "short": "<i2", "int16": "<i2",
             "ushort": "<u2", "uint16": "<u2", "int": "<i4", "int32": "<i4", "uint": "<u4",
             "uint32": "<u4"}
    fields, count, in_vertex = [], 0, False
    for line in raw[:end].decode("ascii", "replace").splitlines():
        w = line.split()
        if w[:1] == ["format"] and w[1] != "binary_little_endian":
            raise ValueError(f"{path}: {w[1]}, expected binary_little_endian")
        if w[:1] == ["element"]:
            in_vertex = w[1] == "vertex"
            if in_vertex: count = int(w[2])
            elif count == 0: raise ValueError(f"{path}: an element before vertex")
        elif w[:1] == ["property"] and in_vertex:
            fields.append((w[2], types[w[1]]))
    return np.frombuffer(raw, dtype=np.dtype(fields), count=count, offset=end)


# ---------------------------------------------------------------- the brute-force ROR count
def ror_brute_force_keep(xyz, radius, others):
    """Exact: keeps a point with >= `others` other points p at ((dx^2 + dy^2) + dz^2) < r^2 in
    float32 (the comparison both sides make; a 1e-4 m change of r moves no point here, printed).
    A numpy grid of cells r/2 wide: two points of one cell are at most 0.87 r apart, so a cell
    holding >= others + 1 points keeps them all; every other point is counted pair by pair against
    the 5 x 5 x 5 cells around its own."""
    import numpy as np
    cell = radius / 2.0
    ijk = np.floor(xyz.astype(np.float64) / cell).astype(np.int64)
    ijk -= ijk.min(axis=0) - 2
    dims = ijk.max(axis=0) + 3
    key = (ijk[:, 0] * dims[1] + ijk[:, 1]) * dims[2] + ijk[:, 2]
    order = np.argsort(key, kind="stable")
    skey = key[order]
    uniq, first, counts = np.unique(skey, return_index=True, return_counts=True)
    per_point = np.empty(len(xyz), np.int64)
    per_point[order] = np.repeat(counts, counts)
    keep = per_point >= others + 1
    todo = np.nonzero(~keep)[0]
    r2 = np.float32(radius * radius)
    neighbours = np.zeros(len(todo), np.int64)
    for dx in range(-2, 3):
        for dy in range(-2, 3):
            for dz in range(-2, 3):
                k = key[todo] + (dx * dims[1] + dy) * dims[2] + dz
                lo = np.searchsorted(skey, k, "left")
                hi = np.searchsorted(skey, k, "right")
                n = hi - lo
                if n.sum() == 0: continue
                q = np.repeat(np.arange(len(todo)), n)
                starts = np.repeat(lo - np.cumsum(n) + n, n)
                cand = order[np.arange(n.sum()) + starts]
                d = xyz[cand] - xyz[todo[q]]
                near = ((d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1]) + d[:, 2] * d[:, 2]) < r2
                near &= cand != todo[q]
                neighbours += np.bincount(q[near], minlength=len(todo))
    keep[todo] = neighbours >= others
    return keep


# ---------------------------------------------------------------- timing
def run_once(cmd, env=None, any_exit=False):
    t0 = time.monotonic()
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env)
    seconds = time.monotonic() - t0
    if p.returncode != 0 and not any_exit:
        raise SystemExit(f"failed ({p.returncode}): {' '.join(map(str, cmd))}\n"
                         f"{p.stderr.decode(errors='replace')[-2000:]}")
    return seconds, p.stdout.decode(errors="replace")


def paired(runs, a, b, warm_up=True):
    """A B A B ... after one warm-up of each; (A times, B times, A/B ratios, A's last stdout,
    B's last stdout)."""
    if warm_up:
        run_once(a["cmd"], a.get("env")); run_once(b["cmd"], b.get("env"))
    ta, tb, outa, outb = [], [], "", ""
    for _ in range(runs):
        s, outa = run_once(a["cmd"], a.get("env")); ta.append(s)
        s, outb = run_once(b["cmd"], b.get("env")); tb.append(s)
    return ta, tb, [x / y for x, y in zip(ta, tb)], outa, outb


def mmm(xs, unit=1.0):
    return f"{min(xs) * unit:8.3f} {statistics.median(xs) * unit:8.3f} {max(xs) * unit:8.3f}"


def row(label, xs):
    print(f"  {label:<44} {mmm(xs)}")


def report(title, name_a, name_b, ta, tb, ratios):
    print(f"\n{title} (process to process, s: min median max; {len(ta)} runs each, paired)")
    row(name_a, ta); row(name_b, tb)
    speedup = [1.0 / r for r in ratios]
    print(f"  {name_b.split()[0]} / {name_a.split()[0]} (pair by pair){'':<20} {mmm(speedup)}  x")


def keel_filter_seconds(stdout):
    out = json.loads(stdout)
    return out, out.get("filter_seconds", float("nan"))


# ---------------------------------------------------------------- the cases
def bench_startup(args, keel):
    print("\nstart-up alone (process to process, s: min median max)")
    cases = [("keel-worker --help", {"cmd": [keel, "--help"]}),
             ("/usr/bin/python3 -c 'import open3d'", {"cmd": [PY, "-c", "import open3d"]})]
    if shutil.which("CloudCompare"):
        # Nothing to do: it loads its plugins, says so and exits 1.
        cases.append(("CloudCompare -SILENT (nothing to do)",
                      {"cmd": ["CloudCompare", "-SILENT"], "env": CC_ENV}))
    for label, c in cases:
        run_once(c["cmd"], c.get("env"), any_exit=True)
        row(label, [run_once(c["cmd"], c.get("env"), any_exit=True)[0] for _ in range(args.runs)])


def bench_filter(args, keel, work, ply, name, chain, o3d_args, runs=None, warm_up=True):
    a = {"cmd": [keel, "filter", "--in", str(ply), "--out", str(work / f"keel_{name}.ply"),
                 "--chain", json.dumps(chain), "--json"]}
    b = {"cmd": [PY, str(HERE), "--open3d-side", name, str(ply), str(work / f"o3d_{name}.ply"),
                 *map(str, o3d_args)]}
    ta, tb, ratios, outa, outb = paired(runs or args.runs, a, b, warm_up)
    report(f"{name}: {json.dumps(chain)} vs Open3D", "keel-worker filter", "Open3D (python3)",
           ta, tb, ratios)
    keel_out, keel_s = keel_filter_seconds(outa)
    o3d_out = json.loads(outb)
    print(f"  in memory (last run, s): Keel {keel_s:.4f}, Open3D {o3d_out['seconds']:.4f}, "
          f"Open3D / Keel {o3d_out['seconds'] / keel_s:.1f} x")
    print(f"  points kept: Keel {keel_out['points_out']}, Open3D {o3d_out['points_out']} "
          f"(of {keel_out['points_in']})")
    return keel_out, o3d_out


def bench_ror(args, keel, work, ply, xyz):
    radius, others = 0.2, 4
    # Keel: keep a point with >= min_neighbors OTHER points within the radius (the kd-tree count
    # includes the point itself and must reach min_neighbors + 1). Open3D 0.16: SearchRadius
    # counts the point itself and keeps it when that count > nb_points, i.e. >= nb_points others.
    # No warm-up run here: Open3D's takes minutes (it lists every neighbour within r of every
    # point), and the map is in the page cache from the cases before.
    keel_out, o3d_out = bench_filter(args, keel, work, ply, "ror",
                                     [{"type": "ror", "radius": radius, "min_neighbors": others}],
                                     [radius, others], args.ror_runs, warm_up=False)
    t0 = time.monotonic()
    brute = ror_brute_force_keep(xyz, radius, others)
    kept = int(brute.sum())
    print(f"  brute force (numpy grid, {time.monotonic() - t0:.1f} s): keeps {kept}; "
          f"Keel - brute {keel_out['points_out'] - kept:+d}, "
          f"Open3D - brute {o3d_out['points_out'] - kept:+d} "
          f"({100.0 * (o3d_out['points_out'] - kept) / kept:+.3f} %)")
    for dr in (-1e-4, 1e-4):
        print(f"  brute force at r {radius + dr:.4f} m keeps "
              f"{int(ror_brute_force_keep(xyz, radius + dr, others).sum())}")


def bench_metrics(args, keel, work, ply):
    r = 0.25
    if not shutil.which("CloudCompare"):
        print("\nmetrics: CloudCompare not installed (Debian: cloudcompare), skipped"); return
    a = {"cmd": [keel, "metrics", "--in", str(ply), "--radius", str(r), "--out",
                 str(work / "keel_metrics.ply"), "--json"]}
    cc = ["CloudCompare", "-SILENT", "-NO_TIMESTAMP", "-AUTO_SAVE", "OFF", "-C_EXPORT_FMT", "PLY",
          "-O", str(ply)]
    save = ["-SAVE_CLOUDS", "FILE", str(work / "cc_metrics.ply")]
    b = {"cmd": cc + ["-DENSITY", str(r), "-TYPE", "SURFACE", "-ROUGH", str(r), "-FEATURE",
                      "PLANARITY", str(r)] + save, "env": CC_ENV}
    # No warm-up: CloudCompare's run takes minutes at 1 M points; the map is in the page cache.
    ta, tb, ratios, outa, _ = paired(args.runs, a, b, warm_up=False)
    report(f"metrics r {r} m: Keel density+roughness+planarity vs CloudCompare's "
           f"-DENSITY SURFACE, -ROUGH, -FEATURE PLANARITY", "keel-worker metrics",
           "CloudCompare -SILENT", ta, tb, ratios)
    # Saved elsewhere: cc_metrics.ply keeps the metrics for the comparison below.
    io_only = [run_once(cc + ["-SAVE_CLOUDS", "FILE", str(work / "cc_io_only.ply")], CC_ENV)[0]
               for _ in range(args.runs)]
    row("CloudCompare -SILENT load + save only", io_only)
    keel_s = json.loads(outa).get("seconds", float("nan"))
    cc_s = statistics.median(tb) - statistics.median(io_only)
    print(f"  in memory (s): Keel {keel_s:.3f} (its own clock), CloudCompare {cc_s:.3f} (median "
          f"full run - median load+save run), CloudCompare / Keel {cc_s / keel_s:.1f} x")
    try:
        import numpy as np
        ours, theirs = read_binary_ply(work / "keel_metrics.ply"), read_binary_ply(work / "cc_metrics.ply")
        names = {"density": "Surface_density", "roughness": "Roughness", "planarity": "Planarity"}
        for k, v in names.items():
            col = next(n for n in theirs.dtype.names if v in n)
            print(f"  mean {k:<10} Keel {np.nanmean(ours[k]):.6g}  CloudCompare "
                  f"{np.nanmean(theirs[col]):.6g}")
    except Exception as e:  # the figures above stand without this check
        print(f"  (per-point means not compared: {e!r})")


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "--open3d-side":
        return open3d_side(*sys.argv[2:])
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("bin", help="folder holding keel-worker (e.g. build/bin)")
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--ror-runs", type=int, help="runs of the ROR case (default: --runs)")
    ap.add_argument("--copies", type=int, default=40)
    ap.add_argument("--work", help="folder for the map and outputs (default: a temporary one)")
    ap.add_argument("--only", default="startup,voxel,ror,metrics")
    args = ap.parse_args()
    keel = str(pathlib.Path(args.bin) / "keel-worker")
    work = pathlib.Path(args.work or tempfile.mkdtemp(prefix="keel-peers-bench-"))
    work.mkdir(parents=True, exist_ok=True)
    load = open("/proc/loadavg").read().split()[:3]
    print(f"load average at start: {' '.join(load)} ({os.cpu_count()} cores); work folder {work}")
    xyz, ply, pcd = make_map(work, args.copies)
    print(f"map: {len(xyz)} points = {args.copies} copies of {SCAN.name}, sigma 0.02 m (2 % 0.5 m), seed 35; "
          f"{ply.name} {ply.stat().st_size / 1e6:.1f} MB, {pcd.name}")
    only = args.only.split(",")
    if "startup" in only: bench_startup(args, keel)
    if "voxel" in only:
        bench_filter(args, keel, work, ply, "voxel", [{"type": "voxel_grid", "leaf": 0.05}], [0.05, 0])
    if "ror" in only: bench_ror(args, keel, work, ply, xyz)
    if "metrics" in only: bench_metrics(args, keel, work, ply)
    if not args.work: shutil.rmtree(work)


if __name__ == "__main__":
    main()
