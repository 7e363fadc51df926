#include "worker/stages/calibrate/keyframe_scans.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "worker/mapping/deskew.h"
#include "worker/mapping/filters.h"
#include "worker/mapping/transform_tree.h"

namespace keel::pipeline {
namespace {

// Half the spacing to the neighbouring keyframes: a scan farther than that from K_j belongs to
// another keyframe (or to none).
std::vector<TimeNs> half_spacings(const std::vector<TimeNs>& keyframes) {
  std::vector<TimeNs> half(keyframes.size(), std::numeric_limits<TimeNs>::max());
  for (size_t j = 0; j < keyframes.size(); ++j) {
    TimeNs spacing = std::numeric_limits<TimeNs>::max();
    if (j > 0) spacing = std::min(spacing, keyframes[j] - keyframes[j - 1]);
    if (j + 1 < keyframes.size()) spacing = std::min(spacing, keyframes[j + 1] - keyframes[j]);
    if (spacing != std::numeric_limits<TimeNs>::max()) half[j] = spacing / 2;
  }
  return half;
}

size_t nearest_keyframe(const std::vector<TimeNs>& keyframes, TimeNs t_ns) {
  const auto it = std::lower_bound(keyframes.begin(), keyframes.end(), t_ns);
  if (it == keyframes.begin()) return 0;
  if (it == keyframes.end()) return keyframes.size() - 1;
  const size_t j = static_cast<size_t>(it - keyframes.begin());
  return (keyframes[j] - t_ns < t_ns - keyframes[j - 1]) ? j : j - 1;
}

}  // namespace

CalibrationScans collect_keyframe_scans(const io::MissionReader& reader,
                                        const std::vector<TimeNs>& keyframes,
                                        const Trajectory& T_world_body,
                                        const std::vector<SensorToCollect>& sensors,
                                        const std::string& reference,
                                        const KeyframeScanOptions& options,
                                        const std::function<void()>& check_canceled) {
  if (keyframes.empty()) throw std::runtime_error("calibrate needs keyframes, found none");
  if (!std::is_sorted(keyframes.begin(), keyframes.end()))
    throw std::runtime_error("calibrate: keyframe stamps are not in time order");
  CalibrationScans out;
  out.reference = reference;
  out.t0_s = ns_to_seconds(keyframes.front());
  for (TimeNs t : keyframes) out.keyframes_t_s.push_back(ns_to_seconds(t - keyframes.front()));
  const std::vector<TimeNs> half = half_spacings(keyframes);

  mapping::TransformTree tree(T_world_body, "body poses");
  mapping::DeskewOptions deskew;
  deskew.max_sweep_duration_s = options.max_sweep_duration_s;
  const mapping::VoxelGridFilter voxel{options.scan_voxel_m};

  for (const SensorToCollect& sensor : sensors) {
    tree.set_extrinsic(sensor.name, sensor.T_body_sensor);
    // Per keyframe, the nearest scan so far: its time distance and the scan itself.
    std::vector<TimeNs> best_dt(keyframes.size(), std::numeric_limits<TimeNs>::max());
    std::vector<PointCloud> best(keyframes.size());
    std::unique_ptr<io::ScanSource> source = reader.open_scans(sensor.name);
    PointCloud scan;
    while (source->next(scan)) {
      check_canceled();
      if (!tree.covers(scan.t_ns)) continue;
      const size_t j = nearest_keyframe(keyframes, scan.t_ns);
      const TimeNs dt = std::abs(scan.t_ns - keyframes[j]);
      if (dt > half[j] || dt >= best_dt[j]) continue;
      best_dt[j] = dt;
      std::swap(best[j], scan);
    }
    CalibrationSensorScans scans{sensor.name, sensor.type, sensor.T_body_sensor, sensor.source, {}};
    for (size_t j = 0; j < keyframes.size(); ++j) {
      if (best_dt[j] == std::numeric_limits<TimeNs>::max()) continue;
      PointCloud& cloud = best[j];
      try {
        mapping::deskew_scan(tree, sensor.name, cloud, deskew);
      } catch (const std::out_of_range&) {
        continue;  // a sweep reaching past the poses' span: the map stage skips it too
      } catch (const std::exception& e) {
        throw std::runtime_error("calibrate: sensor '" + sensor.name + "', scan at " +
                                 std::to_string(ns_to_seconds(cloud.t_ns)) + " s: " + e.what());
      }
      if (options.scan_voxel_m > 0.0) mapping::apply_voxel_grid(voxel, cloud);
      CalibrationScan item;
      item.keyframe = j;
      item.t_s = ns_to_seconds(cloud.t_ns - keyframes.front());
      item.T_world_body = tree.T_world_body(cloud.t_ns);
      item.points = std::move(cloud.xyz);
      scans.scans.push_back(std::move(item));
      cloud = PointCloud();
    }
    out.sensors.push_back(std::move(scans));
  }
  return out;
}

}  // namespace keel::pipeline
