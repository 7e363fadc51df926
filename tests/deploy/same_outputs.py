#!/usr/bin/env python3
"""The demo missions' outputs, byte for byte: a manifest of every artifact's SHA-256.

    same_outputs.py manifest BIN_DIR WORK_DIR > manifest.txt
    same_outputs.py check BIN_DIR WORK_DIR MANIFEST

tests/deploy/demo_outputs.sha256 is the manifest of main before issue 29's restructuring (plus
the compare page that `keel-worker compare` now writes); CTest `deploy/same_outputs` checks it.
A change that alters outputs on purpose regenerates it and says why in its commit.
glibc picks libm's code paths by CPU features (FMA, AVX2), which may move a last bit: the
manifest records the features of the machine that made it, and `check` skips (exit 77),
saying so, on a machine whose features differ.

Runs keel-sim and `keel-worker run` (the pipeline without a server) on the README demo's
missions: usv-bridge (ingest, refine, map), hauv-hull (ingest, refine, ba, inspect), and a
compare of two usv-bridge surveys, then hashes every artifact. A refactoring that keeps
behaviour must keep every hash: `check` fails naming each artifact that differs.

Timings are the one thing not deterministic: in report.json, changes.json and report.html the
values under TIMING_KEYS (wall and CPU seconds, memory peaks) are replaced by "timing" before
hashing, and so is the compare page's table of the figures that differ most (timings rank in
it). Every other byte counts, whatever the thread count: parallel work commits in order, Ceres
solves on one thread over blocks in one buffer, SuiteSparse's memory is aligned.
"""
import hashlib
import json
import os
import re
import shutil
import subprocess
import sys

# Keys whose values measure the machine, not the result; and the names of the `compare` stage's
# run figures ("map.combined.draco.encode_seconds") made of such keys.
TIMING_KEYS = re.compile(
    r"^(.*seconds|.*_time_s|.*wall_s|.*cpu_s|detect_s|deviation_s|fuse_s|.*_rss_mib|"
    r".*points_per_s|.*_per_second)$")


def is_timing_figure(value):
    return (isinstance(value, dict) and isinstance(value.get("figure"), str) and
            any(TIMING_KEYS.match(part) for part in value["figure"].split(".")))

MISSIONS = [
    # name, keel-sim arguments, stages
    ("bridge", ["--scenario", "usv-bridge", "--seed", "1", "--duration", "60"],
     "ingest,refine,map"),
    ("hull", ["--scenario", "hauv-hull", "--seed", "1", "--duration", "60"],
     "ingest,refine,ba,inspect"),
    ("bridge_survey2", ["--scenario", "usv-bridge", "--seed", "1", "--duration", "60",
                        "--survey", "2"], "ingest,refine,map"),
]


def run(cmd):
    done = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if done.returncode != 0:
        sys.stderr.write(done.stdout)
        raise SystemExit(f"failed ({done.returncode}): {' '.join(cmd)}")


def mask_timings(value, key=""):
    if isinstance(value, dict):
        return {k: ("timing" if TIMING_KEYS.match(k) else mask_timings(v, k))
                for k, v in value.items()}
    if isinstance(value, list):
        return [("timing" if is_timing_figure(v) else mask_timings(v, key)) for v in value]
    return value


def masked_pointers(value, pointer=""):
    """JSON pointers of every value mask_timings replaces."""
    out = []
    if isinstance(value, dict):
        for k, v in value.items():
            p = pointer + "/" + k.replace("~", "~0").replace("/", "~1")
            if TIMING_KEYS.match(k):
                out.append(p)
            else:
                out += masked_pointers(v, p)
    elif isinstance(value, list):
        for i, v in enumerate(value):
            out += [f"{pointer}/{i}"] if is_timing_figure(v) else masked_pointers(v, f"{pointer}/{i}")
    return out


def digest(path, report, work):
    data = open(path, "rb").read()
    name = os.path.basename(path)
    # Where the missions were written (report.json's mission path) is not an output.
    data = data.replace(os.path.abspath(work).encode(), b"<work>")
    if name in ("report.json", "changes.json"):
        data = json.dumps(mask_timings(json.loads(data)), sort_keys=False).encode()
    elif name == "report.html" and report is not None:
        # <data value="X" data-pointer="P">X</data>: a timing's value, wherever it is printed.
        text = data.decode("utf-8")
        for pointer in masked_pointers(report):
            p = re.escape(pointer.replace("&", "&amp;").replace('"', "&quot;"))
            text = re.sub(r'<data value="[^"]*" data-pointer="' + p + r'(/[^"]*)?">[^<]*</data>',
                          '<data value="timing">timing</data>', text)
        # The compare page ranks the figures that differ most, timings among them: that
        # table's rows are the timings' order, not a result.
        text = re.sub(r'(<table id="compare-figures">).*?(</table>)', r"\1timing\2", text,
                      flags=re.S)
        # Timings also appear as plain numbers in the timeline; mask "<n> s" cells of it.
        text = re.sub(r'(<section id="summary">.*?</section>)',
                      lambda m: re.sub(r"\d+(\.\d+)? s\b", "timing", m.group(1)), text,
                      flags=re.S)
        data = text.encode()
    return hashlib.sha256(data).hexdigest()


def manifest(bin_dir, work):
    sim, worker = os.path.join(bin_dir, "keel-sim"), os.path.join(bin_dir, "keel-worker")
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    lines = []
    for name, args, stages in MISSIONS:
        mission, out = os.path.join(work, name), os.path.join(work, name + "-out")
        run([sim, *args, "--out", mission])
        run([worker, "run", "--mission", mission, "--stages", stages, "--out", out])
    run([worker, "compare", "--a", os.path.join(work, "bridge-out"),
         "--b", os.path.join(work, "bridge_survey2-out"), "--out", os.path.join(work, "compare-out")])
    for name in ["bridge", "hull", "bridge_survey2", "compare"]:
        out = os.path.join(work, name + "-out")
        report = None
        if os.path.isfile(os.path.join(out, "report.json")):
            text = open(os.path.join(out, "report.json")).read()
            report = json.loads(text.replace(os.path.abspath(work), "<work>"))
        for file in sorted(os.listdir(out)):
            path = os.path.join(out, file)
            if os.path.isfile(path) and not file.startswith("."):
                lines.append(f"{digest(path, report, work)}  {name}/{file}")
    return lines


# The CPU features that select glibc's libm and Eigen/BLAS code paths.
PATH_FEATURES = ("fma", "avx2", "avx512f")


def cpu_features():
    flags = set()
    for line in open("/proc/cpuinfo"):
        if line.startswith("flags"):
            flags = set(line.split(":", 1)[1].split())
            break
    return " ".join(f for f in PATH_FEATURES if f in flags) or "none"


def main():
    if len(sys.argv) < 4 or sys.argv[1] not in ("manifest", "check"):
        raise SystemExit(__doc__)
    if sys.argv[1] == "check":
        recorded = [l for l in open(sys.argv[4]).read().splitlines() if l.startswith("# cpu: ")]
        here = cpu_features()
        if recorded and recorded[0][len("# cpu: "):] != here:
            print(f"skipped: {sys.argv[4]} was made on a CPU with [{recorded[0][7:]}], this one "
                  f"has [{here}]: libm's code paths may differ in the last bit")
            return 77
    lines = manifest(sys.argv[2], sys.argv[3])
    if sys.argv[1] == "manifest":
        print(f"# cpu: {cpu_features()}")
        print("\n".join(lines))
        return 0
    expected = [l for l in open(sys.argv[4]).read().splitlines() if l and not l.startswith("#")]
    want = {l.split("  ", 1)[1]: l.split("  ", 1)[0] for l in expected}
    have = {l.split("  ", 1)[1]: l.split("  ", 1)[0] for l in lines}
    problems = [f"{f}: missing" for f in want if f not in have]
    problems += [f"{f}: not in the manifest (a new artifact?)" for f in have if f not in want]
    problems += [f"{f}: differs" for f in want if f in have and want[f] != have[f]]
    for p in sorted(problems):
        print(p)
    print(f"{len(have)} artifacts, {len(problems)} differ from {sys.argv[4]}")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
