#include <gtest/gtest.h>
#include <cstdio>
#include <algorithm>
#include "tests/worker/ba/ba_synthetic.h"
#include "worker/ba/model_assisted_ba.h"
#include "worker/ba/rig_geometry.h"
#include "worker/ba/surface_factor.h"
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
  if (getenv("ITER")) opt.max_iterations = atoi(getenv("ITER"));
  if (getenv("SEED")) o.seed = atoi(getenv("SEED"));
  if (getenv("INITIT")) opt.initialisation_max_iterations = atoi(getenv("INITIT"));
  if (getenv("BUMP")) o.bump_height_m = atof(getenv("BUMP"));
  auto sim = testing::make_synthetic_hull(o);
  opt.modes = {ba_mode_from_string(getenv("MODE") ? getenv("MODE") : "proposed")};
  auto res = run_model_assisted_ba(sim.problem, opt);
  auto& r = res.modes[0];
  std::printf("cost %.3f -> %.3f iters %d\n", r.initial_cost, r.final_cost, r.iterations);
  std::printf("term: %s\ninit iters %d cost %.1f -> %.1f\n", r.termination.c_str(), res.initialisation.iterations, res.initialisation.initial_cost, res.initialisation.final_cost);
  { Pose3 E = sim.T_world_model.inverse() * res.T_world_model_initial; Eigen::AngleAxisd aa(E.linear());
    std::printf("gicp err in model frame t %.4f %.4f %.4f rotvec deg %.3f %.3f %.3f\n", E.translation().x(), E.translation().y(), E.translation().z(), aa.angle()*aa.axis().x()*57.3, aa.angle()*aa.axis().y()*57.3, aa.angle()*aa.axis().z()*57.3);
    E = sim.T_world_model.inverse() * r.T_world_model; aa = Eigen::AngleAxisd(E.linear());
    std::printf("final err in model frame t %.4f %.4f %.4f rotvec deg %.3f %.3f %.3f\n", E.translation().x(), E.translation().y(), E.translation().z(), aa.angle()*aa.axis().x()*57.3, aa.angle()*aa.axis().y()*57.3, aa.angle()*aa.axis().z()*57.3); }
  { std::vector<double> e; for (auto& l : r.landmarks) e.push_back(l.signed_distance_m - sim.landmark_height_m[l.id]);
    std::sort(e.begin(), e.end()); std::printf("h err percentiles 5/25/50/75/95: %.3f %.3f %.3f %.3f %.3f\n", e[e.size()/20], e[e.size()/4], e[e.size()/2], e[3*e.size()/4], e[19*e.size()/20]); }
  { std::vector<double> e; for (auto& l : r.landmarks) e.push_back((l.position_world - sim.landmarks_world[l.id]).norm());
    std::sort(e.begin(), e.end()); std::printf("pos err percentiles 5/25/50/75/95: %.3f %.3f %.3f %.3f %.3f\n", e[e.size()/20], e[e.size()/4], e[e.size()/2], e[3*e.size()/4], e[19*e.size()/20]);
    MeshQuery cad(sim.problem.cad_mesh); std::vector<double> g; for (auto& l : r.landmarks) g.push_back(signed_distance_to_model(cad, sim.T_world_model, l.position_world) - sim.landmark_height_m[l.id]);
    std::sort(g.begin(), g.end()); std::printf("h err at TRUE xgM 5/25/50/75/95: %.3f %.3f %.3f %.3f %.3f\n", g[g.size()/20], g[g.size()/4], g[g.size()/2], g[3*g.size()/4], g[19*g.size()/20]); }
  { std::vector<double> b; int l0 = 0; for (auto& l : r.landmarks) if (sim.landmark_height_m[l.id] > 0.08) { b.push_back(l.signed_distance_m); l0 += l.lambda == 0; }
    std::sort(b.begin(), b.end()); std::printf("bump h 5/25/50/75/95: %.3f %.3f %.3f %.3f %.3f lambda0 %d/%zu\n", b[b.size()/20], b[b.size()/4], b[b.size()/2], b[3*b.size()/4], b[19*b.size()/20], l0, b.size()); }
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
