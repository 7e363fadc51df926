#include <gtest/gtest.h>
#include <cstdio>
#include "tests/worker/ba/ba_synthetic.h"
#include "worker/ba/model_assisted_ba.h"
#include "worker/ba/rig_geometry.h"
namespace keel::ba {
double rot_err(const Pose3& a, const Pose3& b) { return Eigen::AngleAxisd((a.linear().transpose()*b.linear())).angle(); }
TEST(Debug, Run) {
  testing::SyntheticHullOptions o;
  BaOptions opt;
  o.stereo = getenv("STEREO") != nullptr;
  if (getenv("EXACT")) { o.pixel_noise = 0; o.odometry_noise_m_per_s = 0; o.odometry_noise_rad_per_s = 0; o.depth_noise_m = 0; o.attitude_noise_rad = 0; o.servo_slop_rad = 0; o.dvl_noise_m = 0; o.extrinsic_error_scale = 0; o.model_guess_error_scale = 0; o.initial_pose_drift_m = 0; o.initial_pose_drift_rad = 0; }
  if (getenv("ODO")) { o.odometry_noise_m_per_s = atof(getenv("ODO")); o.odometry_noise_rad_per_s = atof(getenv("ODOR")); }
  if (getenv("PIX")) o.pixel_noise = atof(getenv("PIX"));
  if (getenv("FTOL")) { opt.function_tolerance = atof(getenv("FTOL")); opt.max_iterations = 1000; }
  if (getenv("LIN")) opt.linear_solver = getenv("LIN");
  if (getenv("HUBER")) opt.reprojection_huber = opt.dvl_huber = atof(getenv("HUBER"));
  auto sim = testing::make_synthetic_hull(o);
  opt.modes = {ba_mode_from_string(getenv("MODE") ? getenv("MODE") : "proposed")};
  auto res = run_model_assisted_ba(sim.problem, opt);
  auto& r = res.modes[0];
  std::printf("cost %.3f -> %.3f iters %d\n", r.initial_cost, r.final_cost, r.iterations);
  std::printf("term: %s\n", r.termination.c_str());
  { Pose3 E = sim.T_world_model.inverse() * res.T_world_model_initial; Eigen::AngleAxisd aa(E.linear());
    std::printf("gicp err in model frame t %.4f %.4f %.4f rotvec deg %.3f %.3f %.3f\n", E.translation().x(), E.translation().y(), E.translation().z(), aa.angle()*aa.axis().x()*57.3, aa.angle()*aa.axis().y()*57.3, aa.angle()*aa.axis().z()*57.3);
    E = sim.T_world_model.inverse() * r.T_world_model; aa = Eigen::AngleAxisd(E.linear());
    std::printf("final err in model frame t %.4f %.4f %.4f rotvec deg %.3f %.3f %.3f\n", E.translation().x(), E.translation().y(), E.translation().z(), aa.angle()*aa.axis().x()*57.3, aa.angle()*aa.axis().y()*57.3, aa.angle()*aa.axis().z()*57.3); }
  std::printf("lambda1 per iter:"); for (double f : r.lambda1_fraction_per_iteration) std::printf(" %.3f", f); std::printf("\n");
  std::printf("xgM init err t %.4f r %.4f deg; final t %.4f r %.4f\n", (res.T_world_model_initial.translation()-sim.T_world_model.translation()).norm(), rot_err(res.T_world_model_initial, sim.T_world_model)*57.3,
     (r.T_world_model.translation()-sim.T_world_model.translation()).norm(), rot_err(r.T_world_model, sim.T_world_model)*57.3);
  std::printf("extr init err t %.4f r %.3f; final t %.4f r %.3f\n", (sim.problem.rig.T_servo_camera.translation()-sim.T_servo_camera.translation()).norm(), rot_err(sim.problem.rig.T_servo_camera, sim.T_servo_camera)*57.3,
     (r.T_servo_camera.translation()-sim.T_servo_camera.translation()).norm(), rot_err(r.T_servo_camera, sim.T_servo_camera)*57.3);
  for (size_t i = 0; i < sim.T_world_vehicle.size(); i += 3) {
    std::printf("kf %zu init t %.4f r %.3f servo %.3f | final t %.4f r %.3f servo %.3f deg\n", i,
      (sim.problem.keyframes[i].T_world_vehicle.translation()-sim.T_world_vehicle[i].translation()).norm(), rot_err(sim.problem.keyframes[i].T_world_vehicle, sim.T_world_vehicle[i])*57.3,
      (sim.problem.keyframes[i].servo_angle_rad - sim.servo_angle_rad[i])*57.3,
      (r.T_world_vehicle[i].translation()-sim.T_world_vehicle[i].translation()).norm(), rot_err(r.T_world_vehicle[i], sim.T_world_vehicle[i])*57.3,
      (r.servo_angle_rad[i]-sim.servo_angle_rad[i])*57.3);
  }
}
}
