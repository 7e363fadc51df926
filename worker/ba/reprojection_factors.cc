#include "worker/ba/reprojection_factors.h"

#include <ceres/autodiff_cost_function.h>

namespace keel::ba {
namespace {

// The landmark in the top camera frame: x_sc_T^-1 * x_v_s(theta)^-1 * x_gv^-1 * l.
template <typename T>
Vec3<T> landmark_in_camera(const ServoMount& mount, const T* pose, const T* theta,
                           const T* T_servo_camera, const T* landmark) {
  const Vec3<T> l_world(landmark[0], landmark[1], landmark[2]);
  return inverse_transform_point(T_servo_camera, mount.world_to_servo(pose, theta[0], l_world));
}

struct Monocular {
  PinholeCamera camera;
  ServoMount mount;
  Eigen::Vector2d pixel;
  double sigma_px;

  template <typename T>
  bool operator()(const T* pose, const T* theta, const T* T_servo_camera, const T* landmark,
                  T* residual) const {
    const Vec3<T> p_c = landmark_in_camera(mount, pose, theta, T_servo_camera, landmark);
    const Eigen::Matrix<T, 2, 1> uv = project(camera, p_c);  // Eq. (13)
    residual[0] = (uv[0] - T(pixel[0])) / T(sigma_px);
    residual[1] = (uv[1] - T(pixel[1])) / T(sigma_px);
    return true;
  }
};

struct Stereo {
  PinholeCamera top, bottom;
  Eigen::Quaterniond q_top_bottom;
  Eigen::Vector3d t_top_bottom;
  ServoMount mount;
  Eigen::Vector2d pixel_top, pixel_bottom;
  double sigma_px;

  template <typename T>
  bool operator()(const T* pose, const T* theta, const T* T_servo_camera, const T* landmark,
                  T* residual) const {
    const Vec3<T> p_top = landmark_in_camera(mount, pose, theta, T_servo_camera, landmark);
    // x_cT_cB^-1 maps top-camera points into the bottom camera.
    const Vec3<T> p_bottom = q_top_bottom.cast<T>().conjugate() * (p_top - t_top_bottom.cast<T>());
    const Eigen::Matrix<T, 2, 1> uv_top = project(top, p_top);           // Eq. (12), upper block
    const Eigen::Matrix<T, 2, 1> uv_bottom = project(bottom, p_bottom);  // lower block
    residual[0] = (uv_top[0] - T(pixel_top[0])) / T(sigma_px);
    residual[1] = (uv_top[1] - T(pixel_top[1])) / T(sigma_px);
    residual[2] = (uv_bottom[0] - T(pixel_bottom[0])) / T(sigma_px);
    residual[3] = (uv_bottom[1] - T(pixel_bottom[1])) / T(sigma_px);
    return true;
  }
};

}  // namespace

ceres::CostFunction* make_monocular_factor(const PinholeCamera& camera, const ServoMount& mount,
                                           const Eigen::Vector2d& pixel, double sigma_px) {
  return new ceres::AutoDiffCostFunction<Monocular, 2, kPoseBlockSize, 1, kPoseBlockSize, 3>(
      new Monocular{camera, mount, pixel, sigma_px});
}

ceres::CostFunction* make_stereo_factor(const PinholeCamera& top, const PinholeCamera& bottom,
                                        const Pose3& T_top_bottom, const ServoMount& mount,
                                        const Eigen::Vector2d& pixel_top,
                                        const Eigen::Vector2d& pixel_bottom, double sigma_px) {
  return new ceres::AutoDiffCostFunction<Stereo, 4, kPoseBlockSize, 1, kPoseBlockSize, 3>(
      new Stereo{top, bottom, Eigen::Quaterniond(T_top_bottom.linear()), T_top_bottom.translation(),
                 mount, pixel_top, pixel_bottom, sigma_px});
}

}  // namespace keel::ba
