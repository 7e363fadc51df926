"""Prints the headline figures of a Keel report.json (used by deploy/demo.sh)."""
import json
import sys

report = json.load(open(sys.argv[1]))
stages = report.get("stages", {})

refine = stages.get("refine", {}).get("evaluation", {}).get("table")
if refine:
    print("refine: translational ATE rmse vs ground truth (SE(3) aligned)")
    for name in ("map", "refined_without_dvl", "refined_with_dvl"):
        if name in refine:
            print(f"  {name:22s} {refine[name]['ate']['translation_m']['rmse']:.4f} m")

table = stages.get("map", {}).get("metrics", {}).get("table_v")
if table:
    print(f"map: SLAM map vs inspection map ({table['inspection_map']}), r = 0.25 m (Table V)")
    for row in table["rows"]:
        print(f"  {row['metric']:16s} {row['slam_map']:12.4g} -> {row[table['inspection_map']]:12.4g} {row['unit']}")
    ratios = table["ratios"]
    print(f"  density x{ratios['density_factor']:.1f}, roughness {ratios['roughness_change_percent']:+.0f}%, "
          f"planarity {ratios['planarity_change_percent']:+.0f}%")
