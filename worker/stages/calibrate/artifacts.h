// What the `calibrate` stage writes that others read (docs/calibration.md): calibration.json
// (the refined extrinsics offered for a reprocess) and calibration_scans.bin (one deskewed scan
// per sensor and keyframe, in the sensor frame, with the body pose at its stamp: the data of
// the viewer's calibration page, seed 000 Algorithm 3).
#pragma once

#include <Eigen/Core>

#include <filesystem>
#include <string>
#include <vector>

#include "core/pose.h"

namespace keel::pipeline {

inline constexpr const char* kCalibrationFile = "calibration.json";
inline constexpr const char* kCalibrationScansFile = "calibration_scans.bin";

struct CalibrationScan {
  size_t keyframe = 0;  // index into CalibrationScans::keyframes_t_s
  double t_s = 0.0;     // scan stamp, seconds after t0_s
  Pose3 T_world_body = Pose3::Identity();
  std::vector<Eigen::Vector3f> points;  // sensor frame at t_s, deskewed (m)
};

struct CalibrationSensorScans {
  std::string name;
  std::string type;  // "lidar" | "sonar"
  Pose3 T_body_sensor = Pose3::Identity();
  std::string
      source;  // where T_body_sensor came from: "mission.yaml", "/tf_static", "override ..."
  std::vector<CalibrationScan> scans;  // keyframe order, at most one per keyframe
};

struct CalibrationScans {
  std::string reference;  // the reference sensor's name
  double t0_s = 0.0;      // absolute time (s) that every t_s is relative to
  std::vector<double> keyframes_t_s;
  std::vector<CalibrationSensorScans> sensors;
};

// Writes the file of docs/calibration.md, replacing `path` atomically. Throws
// std::runtime_error naming the path on an I/O failure.
void write_calibration_scans(const std::filesystem::path& path, const CalibrationScans& scans);
// Reads it back, checking the magic, the index and every block's bounds; throws
// std::runtime_error naming the path and what is wrong.
CalibrationScans read_calibration_scans(const std::filesystem::path& path);

}  // namespace keel::pipeline
