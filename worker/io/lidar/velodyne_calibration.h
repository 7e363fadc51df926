// Per-laser geometry of a Velodyne sensor: the driver's calibration YAML (velodyne_pointcloud
// and nebula share its format: num_lasers, distance_resolution, lasers[] of laser_id,
// vert_correction, rot_correction, dist_correction, vert_offset_correction,
// horiz_offset_correction, ...; angles in radians, lengths in metres) or, without a file, the
// model's factory table from its user manual (VLP-16 Table 9-1, VLP-32C Table 9-1, HDL-32E
// Table in Appendix "Laser firing sequence").
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace keel::io::lidar {

enum class VelodyneModel { kVlp16, kVlp32c, kHdl32e };

// "VLP16", "VLP32C", "HDL32E" (the names of mission.yaml's packets.model).
VelodyneModel velodyne_model_from_string(std::string_view name, const std::string& path);
std::string to_string(VelodyneModel model);
size_t laser_count(VelodyneModel model);  // 16, 32, 32
// Factory byte 1205 of a data packet (user manuals, "Factory Bytes").
uint8_t product_id(VelodyneModel model);  // 0x22, 0x28, 0x21

// One laser, indexed by its position in a data block (laser_id). The point in the sensor
// frame (x forward, y left, z up, the ROS drivers' convention) of a return at distance d and
// encoder azimuth a (clockwise seen from above, 0 = forward), with alpha = a - rot_correction:
//   xy = d cos(vert) - vert_offset sin(vert)
//   x  = xy cos(alpha) + horiz_offset sin(alpha)
//   y  = -(xy sin(alpha) - horiz_offset cos(alpha))
//   z  = d sin(vert) + vert_offset cos(vert)
struct VelodyneLaser {
  double vert_rad = 0.0;           // elevation angle
  double rot_rad = 0.0;            // azimuth offset (positive: fires left of the encoder)
  double dist_correction_m = 0.0;  // added to every non-zero distance
  double vert_offset_m = 0.0;
  double horiz_offset_m = 0.0;
  uint16_t ring = 0;  // rank by elevation, 0 = lowest (as the ROS drivers number rings)
  // Cached sin/cos of vert_rad and rot_rad.
  float cos_vert = 1, sin_vert = 0, cos_rot = 1, sin_rot = 0;
};

struct VelodyneCalibration {
  VelodyneModel model = VelodyneModel::kVlp16;
  double distance_resolution_m = 0.002;
  std::vector<VelodyneLaser> lasers;  // laser_count(model) entries, by laser_id

  // Fills cos/sin caches and rings from the angles (after any edit of `lasers`).
  void finalise();
};

// The published factory table of `model` (no per-unit corrections).
VelodyneCalibration factory_calibration(VelodyneModel model);

// Reads the driver's YAML for `model`. Fails (IoError) naming the file and the field: a
// missing field, a laser_id out of range or repeated, a laser count other than the model's,
// a two-point distance correction (HDL-64E only, not decoded here).
VelodyneCalibration load_velodyne_calibration(const std::filesystem::path& file,
                                              VelodyneModel model);
// The same from YAML text; `name` stands for the file in errors.
VelodyneCalibration parse_velodyne_calibration(const std::string& yaml_text, VelodyneModel model,
                                               const std::string& name);

}  // namespace keel::io::lidar
