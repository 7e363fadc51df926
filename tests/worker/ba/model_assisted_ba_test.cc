// Model-assisted BA end to end on a simulated hull patch with a 10 cm bump that is not in the
// CAD (seed 001, Sec. 4.1): `proposed` keeps the bump (labels it lambda = 0), `geva` pulls it
// toward the CAD, `naive` has no surface help. Checked against the simulator's ground truth.
#include "worker/ba/model_assisted_ba.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <numeric>

#include "tests/worker/ba/ba_synthetic.h"
#include "core/mesh_query.h"
#include "worker/ba/surface_factor.h"
#include "worker/ba/triangulation.h"

namespace keel::ba {
namespace {

struct ModeMetrics {
  double bump_mean_height_error_m = 0;  // mean |h_est - h_true| on the bump's top
  double bump_median_height_error_m = 0;
  double bump_mean_signed_error_m = 0;  // mean (h_est - h_true): < 0 is flattening
  double bump_lambda0_fraction = 0;
  double on_model_rms_error_m = 0;  // RMS of h_est - h_true where h_true ~ 0
  double on_model_lambda1_fraction = 0;
  int bump_count = 0, on_model_count = 0;
};

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// h_true is the truth landmark's signed distance to the CAD at the true x_gM; h_est is the
// estimate's at the estimated x_gM (what the inspect stage will use).
ModeMetrics metrics(const testing::SyntheticHull& sim, const BaModeResult& r) {
  ModeMetrics m;
  std::vector<double> bump_abs;
  double on_sq = 0;
  int on_lambda1 = 0, bump_lambda0 = 0;
  for (const BaLandmark& l : r.landmarks) {
    const double h_true = sim.landmark_height_m[l.id];
    if (h_true > 0.08) {
      bump_abs.push_back(std::abs(l.signed_distance_m - h_true));
      m.bump_mean_signed_error_m += l.signed_distance_m - h_true;
      bump_lambda0 += l.lambda == 0;
    } else if (std::abs(h_true) < 0.005) {
      on_sq += (l.signed_distance_m - h_true) * (l.signed_distance_m - h_true);
      on_lambda1 += l.lambda == 1;
      ++m.on_model_count;
    }
  }
  m.bump_count = static_cast<int>(bump_abs.size());
  if (m.bump_count > 0) {
    m.bump_mean_height_error_m =
        std::accumulate(bump_abs.begin(), bump_abs.end(), 0.0) / m.bump_count;
    m.bump_median_height_error_m = median(bump_abs);
    m.bump_mean_signed_error_m /= m.bump_count;
    m.bump_lambda0_fraction = double(bump_lambda0) / m.bump_count;
  }
  if (m.on_model_count > 0) {
    m.on_model_rms_error_m = std::sqrt(on_sq / m.on_model_count);
    m.on_model_lambda1_fraction = double(on_lambda1) / m.on_model_count;
  }
  return m;
}

// Mean (h - h_true) over the bump's top of the features as placed again by their reprojections
// alone (BaLandmark::vision_signed_distance_m, what inspect measures with).
double vision_bump_mean_signed_error(const testing::SyntheticHull& sim, const BaModeResult& r) {
  double sum = 0;
  int n = 0;
  for (const BaLandmark& l : r.landmarks) {
    const double h_true = sim.landmark_height_m[l.id];
    if (h_true > 0.08) sum += l.vision_signed_distance_m - h_true, ++n;
  }
  return n > 0 ? sum / n : 0.0;
}

// Per landmark: the sum of squared reprojection errors (px^2, observations still in front of
// their camera) at the BA's position minus at the vision-only one.
std::vector<double> reprojection_gain(const testing::SyntheticHull& sim, const BaModeResult& r) {
  std::map<int64_t, const FeatureTrack*> tracks;
  for (const FeatureTrack& t : sim.problem.tracks) tracks[t.landmark_id] = &t;
  auto squared = [&](const Eigen::Vector3d& p, const FeatureTrack& track) {
    double sum = 0;
    for (const double e :
         observation_reprojection_errors_px(p, track, r.T_world_camera, sim.problem.rig))
      if (std::isfinite(e)) sum += e * e;
    return sum;
  };
  std::vector<double> gain;
  for (const BaLandmark& l : r.landmarks) {
    const FeatureTrack& track = *tracks.at(l.id);
    gain.push_back(squared(l.position_world, track) - squared(l.vision_position_world, track));
  }
  return gain;
}

void print(const char* name, const BaModeResult& r, const ModeMetrics& m) {
  std::printf(
      "%-9s iters %3d  time %.2fs  cost %.1f -> %.1f  bump |dh| mean %.4f med %.4f "
      "signed %.4f  lambda0 %.2f (n=%d)  on-model rms %.4f lambda1 %.2f (n=%d)\n",
      name, r.iterations, r.solve_time_s, r.initial_cost, r.final_cost, m.bump_mean_height_error_m,
      m.bump_median_height_error_m, m.bump_mean_signed_error_m, m.bump_lambda0_fraction,
      m.bump_count, m.on_model_rms_error_m, m.on_model_lambda1_fraction, m.on_model_count);
}

// Median absolute value: the few beams that hit the bump (not in the CAD) are outliers.
double median_abs(std::vector<double> v) {
  for (double& x : v) x = std::abs(x);
  return median(v);
}

void run_and_check(const testing::SyntheticHullOptions& sim_options) {
  const testing::SyntheticHull sim = testing::make_synthetic_hull(sim_options);
  BaOptions options;
  const BaResult result = run_model_assisted_ba(sim.problem, options);
  ASSERT_EQ(result.modes.size(), 3u);
  const BaModeResult& naive = *result.find(BaMode::kNaive);
  const BaModeResult& geva = *result.find(BaMode::kGeva);
  const BaModeResult& proposed = *result.find(BaMode::kProposed);
  const ModeMetrics mn = metrics(sim, naive), mg = metrics(sim, geva), mp = metrics(sim, proposed);
  print("naive", naive, mn);
  print("geva", geva, mg);
  print("proposed", proposed, mp);
  double servo_sq = 0, servo_sq_measured = 0;
  for (size_t i = 0; i < sim.servo_angle_rad.size(); ++i) {
    servo_sq += std::pow(proposed.servo_angle_rad[i] - sim.servo_angle_rad[i], 2);
    servo_sq_measured +=
        std::pow(sim.problem.keyframes[i].servo_angle_rad - sim.servo_angle_rad[i], 2);
  }
  const double servo_rms = std::sqrt(servo_sq / sim.servo_angle_rad.size());
  const double servo_rms_measured = std::sqrt(servo_sq_measured / sim.servo_angle_rad.size());
  std::printf(
      "landmarks %d/%d, dvl %d/%d, gicp %d fitness %.4g, dvl |r| median initial %.4f "
      "final %.4f, servo rms error %.3f deg (measured %.3f deg)\n",
      result.landmarks_triangulated, result.tracks_in, result.dvl_ranges_used, result.dvl_ranges_in,
      result.gicp_converged, result.gicp_fitness,
      median_abs(residual_values(proposed.dvl_residuals_initial)),
      median_abs(residual_values(proposed.dvl_residuals_final)), servo_rms / kDegToRad,
      servo_rms_measured / kDegToRad);

  ASSERT_GE(mp.bump_count, 30);
  ASSERT_GE(mp.on_model_count, 100);
  for (const BaModeResult* r : {&naive, &geva, &proposed}) {
    EXPECT_LT(r->final_cost, r->initial_cost);
    EXPECT_EQ(r->landmarks.size(), size_t(result.landmarks_triangulated -
                                          result.landmarks_dropped_after_initialisation));
  }
  // The post-initialisation gate leaves no monocular landmark seen fewer than 3 times.
  EXPECT_GT(result.post_initialisation_gate_px, 0.0);
  if (!sim_options.stereo) {
    for (const BaLandmark& l : proposed.landmarks) EXPECT_GE(l.keyframes.size(), 3u);
  }
  // proposed recovers the bump: heights within 1.5 cm, labelled foreign (lambda = 0).
  EXPECT_LT(mp.bump_mean_height_error_m, 0.015);
  EXPECT_LT(std::abs(mp.bump_mean_signed_error_m), 0.015);
  EXPECT_GE(mp.bump_lambda0_fraction, 0.95);
  EXPECT_GE(mp.on_model_lambda1_fraction, 0.95);
  // geva pulls the bump toward the CAD: a clear negative height bias, worse than proposed.
  EXPECT_LT(mg.bump_mean_signed_error_m, -0.02);
  EXPECT_GT(mg.bump_mean_height_error_m, 2.0 * mp.bump_mean_height_error_m);
  // Placed again by their reprojections alone, poses and x_gM held (what inspect measures
  // with): no feature reprojects worse than where the BA left it (the surface factor only
  // adds cost), the bump's heights stay within 1.5 cm, and naive's positions are their own.
  const std::vector<double> vision_gain = reprojection_gain(sim, proposed);
  ASSERT_EQ(vision_gain.size(), proposed.landmarks.size());
  // (Monocular only: for a stereo pair observation_reprojection_errors_px gives the larger of
  // the two cameras' errors, not the sum the factor minimises.)
  if (!sim_options.stereo)
    for (const double gain : vision_gain) EXPECT_GE(gain, -1e-6);
  std::printf("vision alone: bump signed error %.4f, reprojection gain max %.4f px^2\n",
              vision_bump_mean_signed_error(sim, proposed),
              *std::max_element(vision_gain.begin(), vision_gain.end()));
  EXPECT_GT(*std::max_element(vision_gain.begin(), vision_gain.end()), 0.1);  // it moved some
  EXPECT_LT(std::abs(vision_bump_mean_signed_error(sim, proposed)), 0.015);
  for (const BaLandmark& l : naive.landmarks) {
    EXPECT_EQ(l.vision_position_world, l.position_world);
    EXPECT_EQ(l.vision_signed_distance_m, l.signed_distance_m);
  }
  // naive: no surface help, worse on-model landmarks than proposed.
  EXPECT_GT(mn.on_model_rms_error_m, mp.on_model_rms_error_m);
  // Fig. 16 curve: initial state plus one entry per iteration, fractions in [0, 1].
  EXPECT_TRUE(naive.lambda1_fraction_per_iteration.empty());
  ASSERT_FALSE(proposed.lambda1_fraction_per_iteration.empty());
  EXPECT_GE(proposed.lambda1_fraction_per_iteration.size(), size_t(proposed.iterations));
  for (double f : proposed.lambda1_fraction_per_iteration) {
    EXPECT_GE(f, 0.0);
    EXPECT_LE(f, 1.0);
  }
  // The last Fig. 16 entry is the final state's label fraction.
  const double final_fraction = std::count_if(proposed.landmarks.begin(), proposed.landmarks.end(),
                                              [](const BaLandmark& l) { return l.lambda == 1; }) /
                                double(proposed.landmarks.size());
  EXPECT_NEAR(proposed.lambda1_fraction_per_iteration.back(), final_fraction, 0.01);
  // Fig. 17 curve: one entry per Ceres iteration (iteration 0 is the initial state), never
  // rising (rejected steps keep the cost), ending at the final cost.
  for (const BaModeResult* m : {&naive, &geva, &proposed}) {
    ASSERT_EQ(m->cost_per_iteration.size(), size_t(m->iterations));
    EXPECT_DOUBLE_EQ(m->cost_per_iteration.front(), m->initial_cost);
    EXPECT_DOUBLE_EQ(m->cost_per_iteration.back(), m->final_cost);
    for (size_t k = 1; k < m->cost_per_iteration.size(); ++k)
      EXPECT_LE(m->cost_per_iteration[k], m->cost_per_iteration[k - 1]);
    EXPECT_LE(m->unsuccessful_steps, m->iterations);
    EXPECT_GT(m->solve_cpu_s, 0.0);
  }
  // Fig. 18: BA tightens the DVL residuals to about their 3 mm noise; the servo slop (1 deg)
  // is estimated.
  EXPECT_LT(median_abs(residual_values(proposed.dvl_residuals_final)),
            0.5 * median_abs(residual_values(proposed.dvl_residuals_initial)));
  EXPECT_LT(median_abs(residual_values(proposed.dvl_residuals_final)), 0.004);
  EXPECT_LT(servo_rms, 0.5 * servo_rms_measured);
}

TEST(InspectionPoint, RaysTakeOverOnlyWhereTheyPutAnOnModelFeatureSignificantlyOff) {
  BaLandmark l;
  l.position_world = Eigen::Vector3d(1, 2, 3);
  l.signed_distance_m = 0.01;  // pulled in by the surface factor
  l.vision_position_world = Eigen::Vector3d(1, 2, 3.04);
  l.vision_signed_distance_m = 0.05;
  l.lambda = 1;
  l.vision_sigma_m = 0.01;  // 5 sigma off the model by its rays: theirs
  EXPECT_EQ(inspection_point(l).position_world, l.vision_position_world);
  EXPECT_EQ(inspection_point(l).signed_distance_m, 0.05);
  l.vision_sigma_m = 0.02;  // 2.5 sigma: the BA's
  EXPECT_EQ(inspection_point(l).position_world, l.position_world);
  EXPECT_EQ(inspection_point(l).signed_distance_m, 0.01);
  EXPECT_EQ(inspection_point(l, 2.0).signed_distance_m, 0.05);  // at 2 sigmas, theirs again
  l.vision_signed_distance_m = -0.05;                           // behind the model counts the same
  l.vision_sigma_m = 0.01;
  EXPECT_EQ(inspection_point(l).signed_distance_m, -0.05);
  l.vision_sigma_m = std::numeric_limits<double>::infinity();  // rays that do not fix it
  EXPECT_EQ(inspection_point(l).signed_distance_m, 0.01);
  l.vision_sigma_m = 0.01;
  l.lambda = 0;  // already off the model in the BA: the BA's
  EXPECT_EQ(inspection_point(l).signed_distance_m, 0.01);
}

TEST(ModelAssistedBa, MonocularProposedKeepsTheBumpGevaFlattensIt) {
  testing::SyntheticHullOptions o;
  o.bump_height_m = 0.11;  // the cylinder of Fig. 15 and 20, seed 001
  run_and_check(o);
}

TEST(ModelAssistedBa, StereoProposedKeepsTheBumpGevaFlattensIt) {
  testing::SyntheticHullOptions o;
  o.stereo = true;
  o.seed = 11;
  run_and_check(o);
}

// Exact pixels: the noise measured after initialisation is only the model's misfit (0.07 px
// here); the gate's sigma is floored at min_pixel_sigma_px, so exact or synthetic tracks do
// not shrink the gate towards zero (with 1e-12 m of numerical noise it reached ~1e-7 px).
TEST(ModelAssistedBa, PostInitialisationGateSigmaIsFloored) {
  testing::SyntheticHullOptions sim_options;
  sim_options.pixel_noise = 0.0;
  const testing::SyntheticHull sim = testing::make_synthetic_hull(sim_options);
  BaOptions options;
  options.modes = {BaMode::kNaive};
  const BaResult floored = run_model_assisted_ba(sim.problem, options);
  const double sigmas = options.triangulation.post_initialisation_gate_sigmas;
  EXPECT_NEAR(floored.post_initialisation_gate_px,
              sigmas * options.triangulation.min_pixel_sigma_px, 1e-12);
  options.triangulation.min_pixel_sigma_px = 1e-6;  // the measured sigma itself
  const BaResult measured = run_model_assisted_ba(sim.problem, options);
  EXPECT_GT(measured.post_initialisation_gate_px, sigmas * 1e-6);
  EXPECT_LT(measured.post_initialisation_gate_px, floored.post_initialisation_gate_px);
  options.triangulation.min_pixel_sigma_px = 0;
  EXPECT_THROW(run_model_assisted_ba(sim.problem, options), std::invalid_argument);
}

// How many of the landmarks' positions (BA and vision-only) differ in any bit.
int landmarks_differing(const BaModeResult& a, const BaModeResult& b) {
  int n = 0;
  for (size_t k = 0; k < std::min(a.landmarks.size(), b.landmarks.size()); ++k)
    n += a.landmarks[k].position_world != b.landmarks[k].position_world ||
         a.landmarks[k].vision_position_world != b.landmarks[k].vision_position_world;
  return n;
}

void expect_same_bits(const BaModeResult& a, const BaModeResult& b) {
  SCOPED_TRACE(to_string(a.mode));
  EXPECT_EQ(a.cost_per_iteration, b.cost_per_iteration);
  EXPECT_EQ(a.final_cost, b.final_cost);
  EXPECT_EQ(a.T_world_model.matrix(), b.T_world_model.matrix());
  EXPECT_EQ(a.T_servo_camera.matrix(), b.T_servo_camera.matrix());
  EXPECT_EQ(a.model_translation_sigma_m, b.model_translation_sigma_m);
  EXPECT_EQ(a.servo_angle_rad, b.servo_angle_rad);
  ASSERT_EQ(a.T_world_vehicle.size(), b.T_world_vehicle.size());
  int poses_differing = 0;
  for (size_t i = 0; i < a.T_world_vehicle.size(); ++i)
    poses_differing += a.T_world_vehicle[i].matrix() != b.T_world_vehicle[i].matrix();
  EXPECT_EQ(poses_differing, 0);
  ASSERT_EQ(a.landmarks.size(), b.landmarks.size());
  EXPECT_EQ(landmarks_differing(a, b), 0);
}

// The outputs are compared byte for byte between runs, so the BA must give the same bits on
// any number of threads, run after run. With its solves on several threads Ceres summed the
// residual blocks in the order the threads took them (keel-sim hauv-hull's outputs differed at
// 1e-11 from run to run); ba_graph.cc keeps Ceres on one thread and BaOptions::num_threads for
// the mesh queries only.
TEST(ModelAssistedBa, SameBitsOnAnyNumberOfThreads) {
  const testing::SyntheticHull sim = testing::make_synthetic_hull(testing::SyntheticHullOptions{});
  BaOptions options;
  options.num_threads = 1;
  const BaResult one = run_model_assisted_ba(sim.problem, options);
  for (const int threads : {4, 4}) {
    options.num_threads = threads;
    const BaResult many = run_model_assisted_ba(sim.problem, options);
    EXPECT_EQ(many.initialisation.final_cost, one.initialisation.final_cost);
    EXPECT_EQ(many.post_initialisation_gate_px, one.post_initialisation_gate_px);
    EXPECT_EQ(many.T_world_model_initial.matrix(), one.T_world_model_initial.matrix());
    ASSERT_EQ(many.modes.size(), one.modes.size());
    for (size_t m = 0; m < one.modes.size(); ++m) expect_same_bits(one.modes[m], many.modes[m]);
  }
}

TEST(ModelAssistedBa, RejectsBadInputNamingTheField) {
  testing::SyntheticHullOptions o;
  o.landmarks = 50;
  testing::SyntheticHull sim = testing::make_synthetic_hull(o);
  BaProblem bad = sim.problem;
  bad.keyframes[3].t_ns = bad.keyframes[2].t_ns;
  try {
    run_model_assisted_ba(bad);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("keyframes[3].t_ns"), std::string::npos) << e.what();
  }
  bad = sim.problem;
  bad.tracks[1].observations[0].keyframe = 100000;
  EXPECT_THROW(run_model_assisted_ba(bad), std::invalid_argument);
  bad = sim.problem;
  bad.dvl_ranges[0].range_m = std::nan("");
  try {
    run_model_assisted_ba(bad);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("dvl_ranges[0].range_m"), std::string::npos) << e.what();
  }
  bad = sim.problem;
  bad.cad_mesh.faces.clear();
  EXPECT_THROW(run_model_assisted_ba(bad), std::invalid_argument);
  BaOptions options;
  options.sigma1_m = 0;
  try {
    run_model_assisted_ba(sim.problem, options);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("sigma1_m"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ba_mode_from_string("fast"), std::invalid_argument);
  for (int views : {1, 0}) {
    BaOptions few;
    few.triangulation.min_monocular_views = views;
    try {
      run_model_assisted_ba(sim.problem, few);
      FAIL() << "expected std::invalid_argument";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("triangulation.min_monocular_views"), std::string::npos)
          << e.what();
    }
  }
  BaOptions depths;
  depths.frontend.max_depth_m = depths.frontend.min_depth_m;
  EXPECT_THROW(run_model_assisted_ba(sim.problem, depths), std::invalid_argument);
}

}  // namespace
}  // namespace keel::ba
