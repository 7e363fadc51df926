#include "worker/stages/ba/keyframes.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>

#include "worker/mapping/odometry_correction.h"
#include "worker/mapping/stamped_transforms.h"
#include "worker/pipeline/servo_tray.h"

namespace keel::pipeline {

namespace {

using nlohmann::json;

ba::GrayImage to_gray(const io::ImageFrame& frame, const std::string& source) {
  if (frame.bit_depth != 8)
    throw std::runtime_error(source + ": expected an 8-bit image, got " +
                             std::to_string(frame.bit_depth) + "-bit");
  ba::GrayImage gray;
  gray.width = frame.width;
  gray.height = frame.height;
  gray.pixels.resize(size_t(frame.width) * frame.height);
  for (size_t i = 0; i < gray.pixels.size(); ++i) {
    if (frame.channels == 1) {
      gray.pixels[i] = frame.pixels[i];
    } else {  // ITU-R BT.601 luma, as cv::cvtColor does
      const uint8_t* p = &frame.pixels[3 * i];
      gray.pixels[i] = uint8_t(std::lround(0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2]));
    }
  }
  return gray;
}

}  // namespace

BaKeyframes build_keyframes(const io::MissionReader& reader, const BaSensors& s,
                            const BaStageOptions& options, bool decode_images,
                            const StageContext& context) {
  BaKeyframes out;
  const bool has_map = reader.has_trajectory("map");
  const bool has_odometry = reader.has_trajectory("odometry");
  if (!has_map && !has_odometry)
    throw std::runtime_error(
        "ba needs initial poses: mission.yaml has neither trajectories.map nor "
        "trajectories.odometry");
  Trajectory initial;
  std::optional<mapping::StampedTransforms> odometry;
  if (has_odometry) {
    const Trajectory recorded = reader.read_trajectory("odometry");
    odometry.emplace(recorded, "trajectories.odometry");
    initial = has_map ? mapping::correct_odometry(reader.read_trajectory("map"), recorded).refined
                      : recorded;
    out.report["initial_poses"] = has_map ? "trajectories.odometry corrected by trajectories.map "
                                            "(Algorithm 2, seed 000)"
                                          : "trajectories.odometry as recorded";
  } else {
    initial = reader.read_trajectory("map");
    out.report["initial_poses"] = "trajectories.map, interpolated";
  }
  const mapping::StampedTransforms poses(initial, "initial poses");
  const io::ServoSeries servo = reader.read_servo(s.servo->name);
  io::DepthSeries depth;
  if (s.depth) depth = reader.read_depth(s.depth->name);

  auto images = reader.open_images(s.camera->name);
  io::ImageFrame frame;
  size_t skipped = 0;
  while (images->next(frame, decode_images)) {
    context.check_canceled();
    if (options.max_keyframes > 0 && int(out.keyframes.size()) >= options.max_keyframes) break;
    const auto angle = servo_angle_at(servo, frame.t_ns, TimeNs(0.5e9 * options.servo_window_s));
    if (!poses.covers(frame.t_ns) || !angle || (odometry && !odometry->covers(frame.t_ns))) {
      ++skipped;  // outside the poses' or the servo's span
      continue;
    }
    ba::BaKeyframe k;
    k.t_ns = frame.t_ns;
    k.T_world_vehicle = poses.at(frame.t_ns);
    k.servo_angle_rad = *angle;
    if (s.depth) {
      const auto d = io::interpolate_series(depth, frame.t_ns,
                                            [](const io::DepthSample& x) { return x.depth_m; });
      if (d) {
        // World z is up (docs/mission-format.md: depth positive down); roll and pitch as the
        // SLAM estimated them (Z-Y-X Euler of R_world_vehicle).
        const Eigen::Matrix3d& R = k.T_world_vehicle.linear();
        ba::DepthPitchRoll dpr;
        dpr.z_world_m = -*d;
        dpr.pitch_rad = std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
        dpr.roll_rad = std::atan2(R(2, 1), R(2, 2));
        k.depth_pitch_roll = dpr;
      }
    }
    if (decode_images) k.image_top = to_gray(frame, images->current_source());
    out.keyframes.push_back(std::move(k));
  }
  if (out.keyframes.size() < 2)
    throw std::runtime_error("ba: fewer than 2 camera images of '" + s.camera->name +
                             "' fall inside the poses' and the servo's time span");
  if (odometry) {
    for (size_t i = 1; i < out.keyframes.size(); ++i) {
      ba::BaOdometry o;
      o.from = int(i - 1);
      o.to = int(i);
      o.T_from_to =
          odometry->at(out.keyframes[i - 1].t_ns).inverse() * odometry->at(out.keyframes[i].t_ns);
      out.odometry.push_back(o);
    }
    out.report["odometry"] = "trajectories.odometry increments between keyframes";
  } else {
    out.odometry = ba::odometry_from_initial_poses(out.keyframes);
    out.report["odometry"] = "increments of the initial poses (no recorded odometry)";
  }
  out.report["keyframes"] = out.keyframes.size();
  out.report["images_skipped"] = skipped;
  out.report["depth_sensor"] = s.depth ? json(s.depth->name) : json(nullptr);
  return out;
}

}  // namespace keel::pipeline
