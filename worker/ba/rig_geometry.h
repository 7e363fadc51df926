// The HAUV's sensor chain of Fig. 9, seed 001, as templates for auto-differentiation:
//   T_world_camera = x_gv_i (+) x_v_i_s_i(theta) (+) x_sc_T            (Sec. 2.6.3)
//   T_world_dvl    = x_gv_i (+) x_v_i_s_i(theta) (+) T_servo_dvl       (Sec. 2.6.5)
// with x_v_i_s_i(theta) = T_vehicle_servo_zero * Rot(servo_axis, theta).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "worker/ba/ba_problem.h"
#include "worker/ba/pose_block.h"

namespace keel::ba {

// The servo tray's mounting on the vehicle: fixed offset and rotation axis. The offset's
// quaternion is kept next to it so the factors do not convert a matrix per evaluation.
struct ServoMount {
  ServoMount() = default;
  ServoMount(const Pose3& T_vehicle_servo_zero_in, const Eigen::Vector3d& axis_in)
      : T_vehicle_servo_zero(T_vehicle_servo_zero_in),
        axis(axis_in),
        q_vehicle_servo_zero(T_vehicle_servo_zero_in.linear()),
        t_vehicle_servo_zero(T_vehicle_servo_zero_in.translation()) {}

  Pose3 T_vehicle_servo_zero = Pose3::Identity();
  Eigen::Vector3d axis = Eigen::Vector3d::UnitY();
  Eigen::Quaterniond q_vehicle_servo_zero = Eigen::Quaterniond::Identity();
  Eigen::Vector3d t_vehicle_servo_zero = Eigen::Vector3d::Zero();

  // p_servo = x_v_s(theta)^-1 * x_gv^-1 * p_world.
  template <typename T>
  Vec3<T> world_to_servo(const T* T_world_vehicle, const T& theta, const Vec3<T>& p_world) const {
    const Vec3<T> p_vehicle = inverse_transform_point(T_world_vehicle, p_world);
    const Vec3<T> p_servo_zero =
        q_vehicle_servo_zero.cast<T>().conjugate() * (p_vehicle - t_vehicle_servo_zero.cast<T>());
    return axis_angle_rotation(axis, theta).conjugate() * p_servo_zero;
  }

  // p_world = x_gv * x_v_s(theta) * p_servo.
  template <typename T>
  Vec3<T> servo_to_world(const T* T_world_vehicle, const T& theta, const Vec3<T>& p_servo) const {
    const Vec3<T> p_servo_zero = axis_angle_rotation(axis, theta) * p_servo;
    const Vec3<T> p_vehicle =
        q_vehicle_servo_zero.cast<T>() * p_servo_zero + t_vehicle_servo_zero.cast<T>();
    return transform_point(T_world_vehicle, p_vehicle);
  }

  // Direction (no translation) from the servo frame into the world frame.
  template <typename T>
  Vec3<T> servo_direction_to_world(const T* T_world_vehicle, const T& theta,
                                   const Vec3<T>& d_servo) const {
    return block_rotation(T_world_vehicle).normalized() *
           (q_vehicle_servo_zero.cast<T>() * (axis_angle_rotation(axis, theta) * d_servo));
  }

  Pose3 T_vehicle_servo(double theta) const {
    Pose3 rotation = Pose3::Identity();
    rotation.linear() = Eigen::AngleAxisd(theta, axis).toRotationMatrix();
    return T_vehicle_servo_zero * rotation;
  }
};

inline ServoMount servo_mount(const BaRig& rig) {
  return ServoMount{rig.T_vehicle_servo_zero, rig.servo_axis.normalized()};
}

// Pinhole projection with dehomogenisation (Eq. 12-13 leave it implicit).
template <typename T>
Eigen::Matrix<T, 2, 1> project(const PinholeCamera& camera, const Vec3<T>& p_camera) {
  return Eigen::Matrix<T, 2, 1>(T(camera.fx) * p_camera.x() / p_camera.z() + T(camera.cx),
                                T(camera.fy) * p_camera.y() / p_camera.z() + T(camera.cy));
}

// T_world_camera of the top camera for given variables.
inline Pose3 world_camera_pose(const Pose3& T_world_vehicle, double theta, const ServoMount& mount,
                               const Pose3& T_servo_camera) {
  return T_world_vehicle * mount.T_vehicle_servo(theta) * T_servo_camera;
}

}  // namespace keel::ba
