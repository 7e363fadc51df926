// Writes a small, complete mission bundle (files, no bag) whose contents are known in closed
// form, for the mission, reader and ingest tests.
#pragma once

#include <cmath>
#include <filesystem>
#include <string>

#include "io_test_util.h"
#include "worker/io/folder_index.h"
#include "worker/io/image_source.h"
#include "worker/io/cloud/scan_file.h"
#include "worker/io/stream_csv.h"
#include "worker/io/tum.h"

namespace keel::io::testing {

constexpr TimeNs kT0 = 1700000000000000000LL;

struct BundleFigures {
  size_t imu_samples = 401;           // 200 Hz over 2 s
  size_t imu_dropped = 0;             // samples removed to make one gap
  size_t dvl_samples = 41;            // 20 Hz over 2 s
  size_t scans = 5;                   // 10 Hz
  size_t points_per_scan_base = 100;  // scan k has base + 10 k points
  size_t images = 3;
  size_t odometry_poses = 21;  // 10 Hz, moving 1 m/s along x
};

inline std::string bundle_yaml() {
  return R"(keel_mission: 1
name: test-bundle
platform: usv
sensors:
  - name: imu
    type: imu
    file: imu.csv
    rate_hz: 200
    T_body_sensor: {translation: [0, 0, 0], rotation_xyzw: [0, 0, 0, 1]}
  - name: dvl
    type: dvl
    file: dvl.csv
    rate_hz: 20
    T_body_sensor: {translation: [0, 0, -0.3], rotation_xyzw: [0, 0, 0, 1]}
    noise: {velocity_sigma_rel: 2.0e-3}
  - name: lidar_h
    type: lidar
    scans: lidar_h
    rate_hz: 10
    point_time: {field: time, unit: s, reference: scan_start}
    range_m: [0.1, 130.0]
    T_body_sensor: {translation: [0, 0, 0.5], rotation_xyzw: [0, 0, 0, 1]}
  - name: cam0
    type: camera
    images: cam0
    rate_hz: 20
    camera: {model: pinhole, width: 8, height: 6, fx: 5.0, fy: 5.0, cx: 4.0, cy: 3.0, distortion: []}
    T_body_sensor: {translation: [0, 0, 0], rotation_xyzw: [0, 0, 0, 1]}
trajectories:
  odometry: odometry.tum
  map: map_poses.tum
)";
}

// Writes the bundle into `dir`; with `imu_gap`, IMU samples 100..149 (0.25 s) are left out.
inline BundleFigures write_bundle(const std::filesystem::path& dir, bool imu_gap = false) {
  BundleFigures f;
  ImuSeries imu;
  for (size_t i = 0; i < f.imu_samples; ++i) {
    if (imu_gap && i >= 100 && i < 150) continue;
    imu.push_back({kT0 + static_cast<TimeNs>(i) * 5000000, {0, 0, 0.1}, {0, 0, 9.81}});
  }
  if (imu_gap) f.imu_dropped = 50;
  write_imu_csv(dir / "imu.csv", imu);
  DvlSeries dvl;
  for (size_t i = 0; i < f.dvl_samples; ++i)
    dvl.push_back({kT0 + static_cast<TimeNs>(i) * 50000000, {1, 0, 0}, true});
  write_dvl_csv(dir / "dvl.csv", dvl);

  std::filesystem::create_directories(dir / "lidar_h");
  std::vector<IndexEntry> scans;
  for (size_t k = 0; k < f.scans; ++k) {
    PointCloud cloud;
    const size_t n = f.points_per_scan_base + 10 * k;
    for (size_t i = 0; i < n; ++i) {
      cloud.xyz.emplace_back(static_cast<float>(i), static_cast<float>(k), 1.0f);
      cloud.time_s.push_back(0.1f * static_cast<float>(i) /
                             static_cast<float>(n - 1));  // span 0.1 s
    }
    cloud.t_ns = kT0 + static_cast<TimeNs>(k) * 100000000;
    const std::string name = "scan_" + std::to_string(k) + (k % 2 ? ".ply" : ".pcd");
    write_scan_file(dir / "lidar_h" / name, cloud,
                    {ScanEncoding::kBinary, PointTimeEncoding{{"time", proto::TimeUnit::kSeconds,
                                                               proto::TimeReference::kScanStart},
                                                              FieldType::kFloat32}});
    scans.push_back({cloud.t_ns, dir / "lidar_h" / name, 0});
  }
  write_folder_index(dir / "lidar_h", scans);

  std::filesystem::create_directories(dir / "cam0");
  std::vector<IndexEntry> images;
  for (size_t k = 0; k < f.images; ++k) {
    ImageFrame image;
    image.width = 8;
    image.height = 6;
    image.channels = 1;
    image.bit_depth = 8;
    image.pixels.assign(48, static_cast<uint8_t>(40 * k));
    const auto path = dir / "cam0" / ("img_" + std::to_string(k) + ".png");
    write_png(path, image);
    images.push_back({kT0 + static_cast<TimeNs>(k) * 50000000, path, 0});
  }
  write_folder_index(dir / "cam0", images);

  Trajectory odometry, map;
  for (size_t i = 0; i < f.odometry_poses; ++i) {
    const TimeNs t = kT0 + static_cast<TimeNs>(i) * 100000000;
    odometry.push_back(
        {t, make_pose(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.1 * i, 0, 0))});
    if (i % 10 == 0) map.push_back(odometry.back());
  }
  write_tum(dir / "odometry.tum", odometry);
  write_tum(dir / "map_poses.tum", map);
  write_text(dir / "mission.yaml", bundle_yaml());
  return f;
}

}  // namespace keel::io::testing
