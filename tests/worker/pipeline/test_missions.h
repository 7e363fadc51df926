// Tiny missions for the program tests, with contents known by construction.
#pragma once

#include <filesystem>
#include <fstream>
#include <string>

namespace keel::testing {

// One IMU at 10 Hz with 6 samples and a 4-pose odometry (ingest counts 6 and 4).
inline void write_tiny_mission(const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "mission.yaml") << R"(keel_mission: 1
name: tiny
platform: usv
sensors:
  - name: imu
    type: imu
    file: imu.csv
    rate_hz: 10
    T_body_sensor: {translation: [0, 0, 0], rotation_xyzw: [0, 0, 0, 1]}
trajectories:
  odometry: odometry.tum
)";
  std::ofstream imu(dir / "imu.csv");
  imu << "t,wx,wy,wz,ax,ay,az\n";
  for (int i = 0; i < 6; ++i) imu << "1700000000." << i << ",0,0,0.1,0,0,9.81\n";
  std::ofstream odometry(dir / "odometry.tum");
  for (int i = 0; i < 4; ++i) odometry << "1700000000." << i << " " << i << " 0 0 0 0 0 1\n";
}

// A lidar with `scans` sweeps at 10 Hz (one PCD file indexed `scans` times): ingest reads
// them one by one and checks for cancel between them, so it runs for a while.
inline void write_long_mission(const std::filesystem::path& dir, int scans = 20000) {
  std::filesystem::create_directories(dir / "lidar");
  std::ofstream(dir / "mission.yaml") << R"(keel_mission: 1
name: scans
platform: usv
sensors:
  - name: lidar
    type: lidar
    scans: lidar
    rate_hz: 10
    T_body_sensor: {translation: [0, 0, 0], rotation_xyzw: [0, 0, 0, 1]}
trajectories:
  odometry: odometry.tum
)";
  std::ofstream(dir / "lidar" / "s.pcd")
      << "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
         "WIDTH 1\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1\nDATA ascii\n0 0 1\n";
  std::ofstream index(dir / "lidar" / "index.csv");
  index << "t,file\n";
  for (int i = 0; i < scans; ++i) index << 1700000000 + i / 10 << "." << i % 10 << ",s.pcd\n";
  std::ofstream odometry(dir / "odometry.tum");
  for (int i = 0; i < 4; ++i) odometry << "1700000000." << i << " " << i << " 0 0 0 0 0 1\n";
}

}  // namespace keel::testing
