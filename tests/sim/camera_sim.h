// Cameras: pinhole and Kannala-Brandt (OpenCV fisheye: theta_d = theta (1 + k1 theta^2 +
// k2 theta^4 + k3 theta^6 + k4 theta^8)), rendered by casting one ray per pixel, and
// ground-truth feature tracks (landmark projections with an occlusion check).
// Camera frame: x right, y down, z along the optical axis.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <string>
#include <vector>

#include "tests/sim/hull_model.h"
#include "tests/sim/rng.h"
#include "tests/sim/sim_world.h"
#include "core/pose.h"

namespace keel::sim {

struct CameraModel {
  enum class Kind { kPinhole, kKannalaBrandt };
  Kind kind = Kind::kPinhole;
  int width = 640, height = 480;
  double fx = 560.0, fy = 560.0, cx = 319.5, cy = 239.5;
  std::vector<double> distortion;  // kannala_brandt: k1..k4; pinhole: none (not simulated)
  double max_theta_rad = 1.6;      // fisheye: rays beyond this angle see nothing

  std::string model_name() const { return kind == Kind::kPinhole ? "pinhole" : "kannala_brandt"; }
  // Pixel (u, v) -> unit ray in the camera frame; false if outside the lens' field.
  bool unproject(double u, double v, Eigen::Vector3d* ray) const;
  // Camera-frame point -> pixel; false if behind or outside the image.
  bool project(const Eigen::Vector3d& p_camera, Eigen::Vector2d* uv) const;
};

struct CameraRenderOptions {
  double intensity_sigma = 0.007;  // seed 000 Table I, Gaussian white noise (intensity in [0, 1])
  double max_range_m = 60.0;
};

// 8-bit grayscale image.
cv::Mat render_image(const SimWorld& world, const CameraModel& camera, const Pose3& T_world_camera,
                     const CameraRenderOptions& options, Rng& rng);

struct TrackObservation {
  int64_t landmark_id;
  double u, v;
};

// Landmarks visible from the camera: in the image (2 px margin), facing it and not occluded.
std::vector<TrackObservation> visible_landmarks(const SimWorld& world, const CameraModel& camera,
                                                const Pose3& T_world_camera,
                                                const std::vector<Landmark>& landmarks,
                                                double max_range_m = 8.0);

}  // namespace keel::sim
