#include <gtest/gtest.h>
#include <cstdio>
#include "tests/worker/ba/ba_synthetic.h"
#include "worker/ba/model_assisted_ba.h"
#include "worker/ba/rig_geometry.h"
namespace keel::ba {
double rot_err(const Pose3& a, const Pose3& b) { return Eigen::AngleAxisd((a.linear().transpose()*b.linear())).angle(); }
TEST(Debug, Run) {
  testing::SyntheticHullOptions o;
  o.stereo = getenv("STEREO") != nullptr;
  auto sim = testing::make_synthetic_hull(o);
  BaOptions opt;
  opt.modes = {ba_mode_from_string(getenv("MODE") ? getenv("MODE") : "proposed")};
  auto res = run_model_assisted_ba(sim.problem, opt);
  auto& r = res.modes[0];
  std::printf("term: %s\n", r.termination.c_str());
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
