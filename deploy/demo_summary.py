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

ba = stages.get("ba", {}).get("modes")
if ba:
    print("ba: model-assisted bundle adjustment per mode (seed 001 Sec. 4)")
    for name in ("naive", "geva", "proposed"):
        if name in ba:
            m = ba[name]
            r = m['dvl_residuals_final']
            print(f"  {name:9s} {m['solve_time_s']:6.2f} s {m['iterations']:3d} iterations, "
                  f"DVL range residual sigma {r['sigma_m']:.4f} m "
                  f"(robust {r['robust_sigma_m']:.4f} m; GICP alone "
                  f"{m['dvl_residuals_gicp']['sigma_m']:.4f} m)")

inspect = stages.get("inspect", {})
if "shapes" in inspect:
    print(f"inspect: {len(inspect['shapes'])} shapes off the CAD model (tau {inspect['tau_m']:.4f} m)")
    for obj in inspect.get("truth", {}).get("objects", []):
        found = (f"found, measured {obj['measured_height_m']:.3f} m" if obj["found"] else
                 f"not found (nearest shape {obj['nearest_shape_distance_m']:.2f} m away)"
                 if obj.get("nearest_shape_distance_m") is not None else "not found (no shape)")
        print(f"  {obj['kind']:8s} true height {obj['true_height_m']:.3f} m: {found}")
