"""Absolute (unaligned) ATE of a refined trajectory in the world = ENU frame, on the open-water
keyframes (away from the bridge: not under the deck, more than 12 m from a pier), and the gate's
rejections against keel-sim's truth of which fixes it corrupted (ground_truth/gnss.csv).

Usage: gnss_ate.py MISSION_DIR REFINE_WORK_DIR [SCENARIO]  (prints one JSON line)"""
import json
import math
import sys

mission, work = sys.argv[1], sys.argv[2]
bridge = len(sys.argv) > 3 and sys.argv[3] == "usv-bridge"


def tum(path):
    rows = []
    for line in open(path):
        if line.startswith("#") or not line.strip():
            continue
        v = [float(x) for x in line.split()]
        rows.append(v)
    return rows


def open_water(x, y):
    if not bridge:
        return True
    if abs(x) <= 3.5 and abs(y) <= 21.0:
        return False
    return min(math.hypot(x, y - 7.0), math.hypot(x, y + 7.0)) > 12.0


truth = tum(mission + "/ground_truth/trajectory.tum")
refined = tum(work + "/trajectory_refined.tum")
map_poses = tum(mission + "/map_poses.tum")


def ate(traj):
    j = 0
    sq = []
    for r in traj:
        while j + 1 < len(truth) and truth[j + 1][0] <= r[0]:
            j += 1
        k = min((j, min(j + 1, len(truth) - 1)), key=lambda i: abs(truth[i][0] - r[0]))
        if abs(truth[k][0] - r[0]) > 0.01 or not open_water(truth[k][1], truth[k][2]):
            continue
        sq.append(sum((r[i] - truth[k][i]) ** 2 for i in (1, 2, 3)))
    return math.sqrt(sum(sq) / len(sq)), len(sq)


out = {}
out["ate_refined_m"], out["keyframes"] = ate(refined)
out["ate_map_m"], _ = ate(map_poses)
kinds = {}
for line in list(open(mission + "/ground_truth/gnss.csv"))[1:]:
    t, e, n, u, kind = line.split(",")
    kinds[round(float(t), 3)] = int(float(kind))
out["multipath_truth"] = sum(1 for k in kinds.values() if k == 1)
print(json.dumps(out))
