// Stages `ba` then `inspect` on a short keel-sim hauv-hull mission: the artifacts exist and
// decode (Draco round trip of the remeshed hull with its per-vertex deviation, shapes.json,
// ba_solution.json, trajectory_ba.tum), model-assisted BA shrinks the DVL range residuals below
// GICP alone (Fig. 18), the lambda = 1 fractions are fractions (Fig. 16), and option errors
// name the option. Tracks are the simulator's ground-truth tracks (truth.yaml), not the frontend.
//
// The 0.11 m cylinder sits on the second survey lane, which a mission short enough for a unit
// test does not reach; its height is checked by tests/bench/hull_sim_bench.cc.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>

#include "core/mesh_query.h"
#include "tests/error_of.h"
#include "tests/worker/pipeline/sim_mission.h"
#include "tests/worker/pipeline/stage_run.h"
#include "worker/io/draco/draco_codec.h"
#include "worker/io/mesh/mesh_reader.h"
#include "worker/io/tum.h"
#include "worker/io/yaml_json.h"
#include "worker/stages/ba/stage.h"
#include "worker/stages/inspect/stage.h"

namespace keel::pipeline {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr uint64_t kSeed = 3;

fs::path temp_root() {
  return fs::temp_directory_path() / ("keel_hull_stages_" + std::to_string(::getpid()));
}

// One short simulated hull mission (first survey lane), shared by the tests of this file.
fs::path simulated_mission() {
  const fs::path dir = temp_root() / "hull";
  if (fs::exists(dir / "mission.yaml")) return dir;
  return testing::simulate(dir, "hauv-hull", kSeed, 20.0);
}

StageResult run_stage(Stage& stage, const fs::path& mission, const json& options,
                      const fs::path& work_dir) {
  return testing::run_stage(stage, mission, options, work_dir).result;
}

std::string error_of(Stage& stage, const json& options, const fs::path& work_dir) {
  return keel::testing::error_of([&] { run_stage(stage, simulated_mission(), options, work_dir); });
}

json read_json(const fs::path& path) {
  std::ifstream in(path);
  return json::parse(in);
}

// The table's rows per state match the report's counts, and every hit point lies on the CAD
// mesh (in its own frame) within 1e-6 m.
void expect_dvl_residual_table(const fs::path& table, const fs::path& cad, const json& mode) {
  std::ifstream in(table);
  std::string line;
  ASSERT_TRUE(std::getline(in, line)) << table;
  EXPECT_EQ(line, "state,t,x_model_m,y_model_m,z_model_m,residual_m");
  const keel::MeshQuery query(io::read_mesh(cad));
  std::map<std::string, int> rows;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string state, t;
    double x, y, z, residual;
    char comma;
    std::getline(fields, state, ','), std::getline(fields, t, ',');
    fields >> x >> comma >> y >> comma >> z >> comma >> residual;
    ASSERT_TRUE(fields && std::isfinite(residual)) << line;
    ++rows[state];
    EXPECT_LT(std::abs(query.signed_distance({x, y, z})), 1e-6) << line;
  }
  EXPECT_EQ(rows["gicp"], mode["dvl_residuals_gicp"]["count"].get<int>());
  EXPECT_EQ(rows["ba"], mode["dvl_residuals_final"]["count"].get<int>());
  EXPECT_EQ(rows.size(), 2u);
}

class HullStagesTest : public ::testing::Test {
 protected:
  static void TearDownTestSuite() { fs::remove_all(temp_root()); }
};

TEST_F(HullStagesTest, BaThenInspectOnSimulatedHull) {
  const fs::path mission = simulated_mission();
  const fs::path work = temp_root() / "work";
  const json ba_options = {{"tracks", "ground_truth"}};
  const StageResult ba = run_stage(*make_ba_stage(), mission, ba_options, work);
  const json& r = ba.report;
  json summary = r;
  summary.erase("modes");
  SCOPED_TRACE(summary.dump());

  // Every mode ran, from the same GICP alignment.
  for (const char* mode : {"naive", "geva", "proposed"}) {
    ASSERT_TRUE(r["modes"].contains(mode)) << mode;
    const json& m = r["modes"][mode];
    EXPECT_GT(m["iterations"].get<int>(), 0) << mode;
    EXPECT_LE(m["final_cost"].get<double>(), m["initial_cost"].get<double>()) << mode;
    for (const auto& f : m["lambda1_fraction_per_iteration"]) {
      EXPECT_GE(f.get<double>(), 0.0) << mode;
      EXPECT_LE(f.get<double>(), 1.0) << mode;
    }
  }
  EXPECT_TRUE(r["modes"]["naive"]["lambda1_fraction_per_iteration"].empty());
  EXPECT_FALSE(r["modes"]["proposed"]["lambda1_fraction_per_iteration"].empty());

  // Fig. 18: the DVL range residuals after the proposed BA are tighter than after GICP alone.
  const json& proposed = r["modes"]["proposed"];
  const double sigma_gicp = proposed["dvl_residuals_gicp"]["sigma_m"].get<double>();
  const double sigma_ba = proposed["dvl_residuals_final"]["sigma_m"].get<double>();
  EXPECT_GT(proposed["dvl_residuals_final"]["count"].get<int>(), 20);
  EXPECT_LT(sigma_ba, sigma_gicp);
  // The histogram counts every residual.
  const json& h = proposed["dvl_residuals_final"]["histogram"];
  int counted = h["below"].get<int>() + h["above"].get<int>();
  for (const auto& c : h["counts"]) counted += c.get<int>();
  EXPECT_EQ(counted, proposed["dvl_residuals_final"]["count"].get<int>());
  // dvl_residuals.csv (Fig. 18(a)-(b)): a row per beam and state, each hit on the CAD mesh.
  expect_dvl_residual_table(work / kBaDvlResidualsFile, mission / "cad" / "hull.ply", proposed);

  // x_gM's error against truth.yaml's T_world_cad is reported per model axis too (the
  // formula: ModelError.IsAlongTheTrueModelAxes).
  for (const json* solved : {&proposed, &r["gicp"]}) {
    const json& e = (*solved)["T_world_model_vs_truth"];
    ASSERT_EQ(e["translation_error_model_axes_m"].size(), 3u);
    const Eigen::Vector3d axes(e["translation_error_model_axes_m"][0].get<double>(),
                               e["translation_error_model_axes_m"][1].get<double>(),
                               e["translation_error_model_axes_m"][2].get<double>());
    EXPECT_NEAR(axes.norm(), e["translation_error_m"].get<double>(), 1e-12);
    // Across the hull (model y, z) the DVL ranges fix x_gM to centimetres; along it (x) this
    // short mission over the prismatic mid-body leaves it to the 1 m prior (1.4 m off here).
    EXPECT_LT(std::hypot(axes.y(), axes.z()), 0.15);
  }
  // The covariance says so too: x_gM's translation sigma along the hull is many times the
  // sigma across it, and no more than its 1 m prior's.
  const json& sigma = proposed["T_world_model_translation_sigma_model_axes_m"];
  ASSERT_EQ(sigma.size(), 3u) << sigma.dump();
  const double along = sigma[0].get<double>();
  EXPECT_GT(along, 5.0 * std::max(sigma[1].get<double>(), sigma[2].get<double>()));  // 0.82 m
  EXPECT_LE(along, 1.0 + 1e-9);  // a posterior sigma never exceeds the prior's

  // Artifacts: one refined pose per keyframe; the solution reads back.
  const Trajectory refined = io::read_tum(work / kBaTrajectoryFile);
  EXPECT_EQ(refined.size(), r["input"]["keyframes"].get<size_t>());
  const BaSolution solution =
      ba_solution_from_json(read_json(work / kBaSolutionFile), kBaSolutionFile);
  EXPECT_EQ(solution.mode, "proposed");
  EXPECT_EQ(solution.T_world_camera.size(), refined.size());
  ASSERT_FALSE(solution.landmarks.empty());
  for (const auto& l : solution.landmarks) EXPECT_TRUE(l.lambda == 0 || l.lambda == 1);

  // inspect: the remeshed CAD decodes with one deviation per vertex.
  const StageResult in = run_stage(*make_inspect_stage(), mission, json::object(), work);
  SCOPED_TRACE(in.report.dump(1).substr(0, 4000));
  const TriangleMesh cad = io::read_mesh(mission / "cad" / "hull.ply");
  const io::DracoMesh decoded =
      io::decode_draco_mesh(io::read_draco_file(work / kRemeshedDracoFile), kRemeshedDracoFile);
  EXPECT_EQ(decoded.mesh.num_faces(), cad.num_faces());
  ASSERT_EQ(decoded.fields.size(), 1u);
  EXPECT_EQ(decoded.fields[0].name, "deviation");
  EXPECT_EQ(decoded.fields[0].values.size(), decoded.mesh.num_vertices());
  // The remeshed hull stays where x_gM put the CAD: vertices move only by the deviations.
  const Pose3 T_world_model = solution.T_world_model;
  double max_move = 0;
  for (size_t i = 0; i < std::min<size_t>(cad.num_vertices(), 200); ++i) {
    double nearest = 1e9;
    for (const auto& v : decoded.mesh.vertices)
      nearest = std::min(nearest, (v.cast<double>() - T_world_model * cad.vertices[i]).norm());
    max_move = std::max(max_move, nearest);
  }
  EXPECT_LT(max_move, 0.5);
  EXPECT_TRUE(fs::is_regular_file(work / kRemeshedPlyFile));
  const json shapes = read_json(work / kShapesFile);
  ASSERT_TRUE(shapes.contains("shapes"));
  EXPECT_EQ(shapes["shapes"].size(), in.report["shapes"].size());
  ASSERT_TRUE(in.report.contains("truth"));
  const json truth = io::load_yaml_file(mission / "ground_truth" / "truth.yaml");
  EXPECT_EQ(in.report["truth"]["objects"].size(), truth["foreign_objects"].size());
}

TEST(ModelError, IsAlongTheTrueModelAxes) {
  // The true model frame is turned 90 degrees about z, so its x axis is the world's y: an
  // estimate 0.1 m along world y and 0.05 m along world z is 0.1 m along the model's x.
  Pose3 truth = Pose3::Identity();
  truth.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  truth.translation() = Eigen::Vector3d(1.0, 2.0, 3.0);
  Pose3 estimate = truth;
  estimate.translation() += Eigen::Vector3d(0.0, 0.1, 0.05);
  estimate.linear() =
      truth.linear() *
      Eigen::AngleAxisd(2.0 * M_PI / 180.0, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const json e = model_error(estimate, truth);
  const std::vector<double> axes = e["translation_error_model_axes_m"].get<std::vector<double>>();
  ASSERT_EQ(axes.size(), 3u);
  EXPECT_NEAR(axes[0], 0.1, 1e-12);
  EXPECT_NEAR(axes[1], 0.0, 1e-12);
  EXPECT_NEAR(axes[2], 0.05, 1e-12);
  EXPECT_NEAR(e["translation_error_m"].get<double>(), std::hypot(0.1, 0.05), 1e-12);
  EXPECT_NEAR(e["rotation_error_deg"].get<double>(), 2.0, 1e-9);
}

TEST_F(HullStagesTest, FunctionToleranceReachesTheSolver) {
  // Ceres stops once an iteration gains less than function_tolerance of the cost: a loose
  // tolerance must stop `naive` sooner than the default 1e-6, and say why it stopped.
  const fs::path mission = simulated_mission();
  auto naive_solve = [&](double tolerance, const std::string& dir) {
    const json options = {
        {"tracks", "ground_truth"}, {"mode", "naive"}, {"function_tolerance", tolerance}};
    return run_stage(*make_ba_stage(), mission, options, temp_root() / dir)
        .report["modes"]["naive"];
  };
  const json strict = naive_solve(1e-6, "tolerance_strict");
  const json loose = naive_solve(0.1, "tolerance_loose");
  EXPECT_LT(loose["iterations"].get<int>(), strict["iterations"].get<int>());
  EXPECT_NE(loose["termination"].get<std::string>().find("Function tolerance"), std::string::npos)
      << loose["termination"];
}

TEST_F(HullStagesTest, OptionErrorsNameTheOption) {
  const fs::path work = temp_root() / "work_errors";
  auto ba = make_ba_stage();
  EXPECT_NE(error_of(*ba, {{"mode", "best"}}, work).find("options.ba.mode"), std::string::npos);
  EXPECT_NE(error_of(*ba, {{"modes", "all"}}, work).find("options.ba.modes: unknown option"),
            std::string::npos);
  EXPECT_NE(error_of(*ba, {{"tracks", "magic"}}, work).find("options.ba.tracks"),
            std::string::npos);
  EXPECT_NE(error_of(*ba, {{"max_iterations", 0}}, work).find("options.ba.max_iterations"),
            std::string::npos);
  for (const double bad : {0.0, 1.0, -1e-6})
    EXPECT_NE(
        error_of(*ba, {{"function_tolerance", bad}}, work).find("options.ba.function_tolerance"),
        std::string::npos)
        << bad;
  EXPECT_NE(
      error_of(*ba, {{"dvl_range_normal", "vertex"}}, work).find("options.ba.dvl_range_normal"),
      std::string::npos);
  auto inspect = make_inspect_stage();
  EXPECT_NE(error_of(*inspect, {{"tau_m", -1.0}}, work).find("tau_m"), std::string::npos);
  EXPECT_NE(error_of(*inspect, {{"alpha", 0.1}}, work).find("options.inspect.alpha"),
            std::string::npos);
  // Without a ba stage before it, inspect names the missing file.
  EXPECT_NE(error_of(*inspect, json::object(), temp_root() / "empty").find(kBaSolutionFile),
            std::string::npos);
}

TEST(HullStagesRegistry, BaAndInspectAreBuiltIn) {
  EXPECT_EQ(make_stage("ba")->name(), "ba");
  EXPECT_EQ(make_stage("inspect")->name(), "inspect");
}

TEST(BaSolutionJson, RoundTripsAndRejectsBadViews) {
  BaSolution s;
  s.mode = "proposed";
  s.T_world_model = make_pose(Eigen::Quaterniond(Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitZ())),
                              Eigen::Vector3d(1, 2, 3));
  s.t_ns = {10, 20};
  s.T_world_camera = {Pose3::Identity(), s.T_world_model};
  s.landmarks.push_back({7, Eigen::Vector3d(0.5, -1, 2), 0.04, 1, {0, 1}});
  const BaSolution back = ba_solution_from_json(ba_solution_to_json(s), "doc");
  EXPECT_TRUE(back.T_world_model.isApprox(s.T_world_model, 1e-12));
  ASSERT_EQ(back.landmarks.size(), 1u);
  EXPECT_EQ(back.landmarks[0].views, (std::vector<int>{0, 1}));
  EXPECT_EQ(back.t_ns, s.t_ns);
  json bad = ba_solution_to_json(s);
  bad["landmarks"][0]["views"] = {0, 2};
  try {
    ba_solution_from_json(bad, "doc");
    FAIL() << "out-of-range view accepted";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("doc.landmarks[0].views"), std::string::npos) << e.what();
  }
}

TEST(ResidualStats, RobustSigmaIgnoresTheFewBeamsOnUnmodelledStructure) {
  // 0.001 m * {-3, -1, 0, 1, 3} and one beam on a patch 0.15 m proud (observed range shorter).
  const std::vector<double> r = {-0.003, -0.001, 0.0, 0.001, 0.003, -0.15};
  const json s = residual_stats(r, BaStageOptions{});
  // Median -0.0005; |r - median| sorted = {0.0005, 0.0005, 0.0015, 0.0025, 0.0035, 0.1495},
  // whose median is 0.002.
  EXPECT_NEAR(s["robust_sigma_m"].get<double>(), 1.4826 * 0.002, 1e-12);
  EXPECT_NEAR(s["percentiles_m"]["p50"].get<double>(), -0.0005, 1e-15);
  double mean = 0, var = 0;
  for (double x : r) mean += x / r.size();
  for (double x : r) var += (x - mean) * (x - mean) / r.size();
  EXPECT_NEAR(s["sigma_m"].get<double>(), std::sqrt(var), 1e-15);  // 0.056 m: the one beam
  EXPECT_EQ(s["histogram"]["below"].get<int>(), 1);
}

TEST(ResidualStats, RobustSigmaOfAGaussianIsItsSigma) {
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.004);
  std::vector<double> r(20001);
  for (double& x : r) x = noise(rng);
  // The sample MAD's relative standard error is ~1.17 / sqrt(n) (~0.8 %).
  EXPECT_NEAR(residual_stats(r, BaStageOptions{})["robust_sigma_m"].get<double>(), 0.004, 1e-4);
}

}  // namespace
}  // namespace keel::pipeline
