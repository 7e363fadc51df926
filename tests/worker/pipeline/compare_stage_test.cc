// The compare stage on synthetic job folders: a scene and its later survey (a block added, a
// known rigid offset), a hull job, and the refusals (map vs hull, other project, unfinished).
#include "worker/stages/compare/stage.h"

#include <gtest/gtest.h>

#include <set>

#include <unistd.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>

#include "proto/contract_error.h"
#include "tests/error_of.h"
#include "tests/worker/compare/test_surfaces.h"
#include "worker/io/draco/draco_codec.h"
#include "worker/pipeline/draco_sidecar.h"
#include "worker/pipeline/report.h"
#include "worker/stages/ba/stage.h"
#include "worker/stages/compare/compare_runs.h"
#include "worker/stages/inspect/stage.h"
#include "worker/stages/map/stage.h"

namespace keel::pipeline {
namespace {

namespace fs = std::filesystem;
using compare::testing::sample_box;
using compare::testing::sample_rectangle;
using nlohmann::json;

class CompareStageTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / ("keel_compare_stage_" + std::to_string(::getpid()));
    fs::remove_all(root_);
    fs::create_directories(root_);
  }
  void TearDown() override { fs::remove_all(root_); }

  // A scene of floor, walls and boxes; `changed` adds a 10 cm slab on the floor.
  std::vector<Eigen::Vector3f> scene(uint32_t seed, bool changed) {
    std::mt19937 rng(seed);
    std::vector<Eigen::Vector3f> p;
    const Eigen::Vector3d X = Eigen::Vector3d::UnitX(), Y = Eigen::Vector3d::UnitY(),
                          Z = Eigen::Vector3d::UnitZ();
    const double density = 2500, sigma = 0.004;
    if (changed) {  // the floor but under the slab [5, 6.5] x [3.5, 4.5], which hides it
      sample_rectangle({0, 0, 0}, X, 8, Y, 3.5, density, sigma, rng, &p);
      sample_rectangle({0, 4.5, 0}, X, 8, Y, 1.5, density, sigma, rng, &p);
      sample_rectangle({0, 3.5, 0}, X, 5, Y, 1, density, sigma, rng, &p);
      sample_rectangle({6.5, 3.5, 0}, X, 1.5, Y, 1, density, sigma, rng, &p);
    } else {
      sample_rectangle({0, 0, 0}, X, 8, Y, 6, density, sigma, rng, &p);
    }
    sample_rectangle({0, 6, 0}, X, 8, Z, 3, density, sigma, rng, &p);
    sample_rectangle({0, 0, 0}, Y, 6, Z, 3, density, sigma, rng, &p);
    sample_box({2, 2, 0}, {3, 3.5, 1.5}, density, sigma, rng, &p);
    sample_box({5, 1, 0}, {6.5, 1.6, 0.8}, density, sigma, rng, &p);
    if (changed) {  // the slab's top and sides
      sample_rectangle({5, 3.5, 0.1}, X, 1.5, Y, 1, density, sigma, rng, &p);
      sample_rectangle({5, 3.5, 0}, X, 1.5, Z, 0.1, density, sigma, rng, &p);
      sample_rectangle({5, 4.5, 0}, X, 1.5, Z, 0.1, density, sigma, rng, &p);
      sample_rectangle({5, 3.5, 0}, Y, 1, Z, 0.1, density, sigma, rng, &p);
      sample_rectangle({6.5, 3.5, 0}, Y, 1, Z, 0.1, density, sigma, rng, &p);
    }
    return p;
  }

  // A job folder with map_combined.drc and report.json.
  InputJob map_job(const std::string& name, const std::vector<Eigen::Vector3f>& points,
                   const json& record = json::object()) {
    InputJob job;
    job.dir = root_ / name;
    fs::create_directories(job.dir);
    io::write_draco_file(job.dir / map_draco_file(kCombinedMapName),
                         io::encode_draco_point_cloud(points, {}, {18, 12, 5}).bytes);
    write_report(job.dir, {{"map", {{"points", points.size()}, {"radius_m", 0.25}}}});
    job.job = {
        {"id", name}, {"state", "succeeded"}, {"project", "p1"}, {"mission_id", "m_" + name}};
    job.job.update(record);
    return job;
  }

  void write_report(const fs::path& dir, const json& stages) {
    std::ofstream(dir / kReportFileName) << json{{"keel_report", 1}, {"stages", stages}}.dump();
  }

  StageResult run(std::vector<InputJob> jobs, const json& options = json::object()) {
    StageContext context;
    context.work_dir = root_ / "out";
    fs::create_directories(context.work_dir);
    context.options = options;
    context.input_jobs = std::move(jobs);
    return make_compare_stage()->run(context);
  }

  std::string refusal(std::vector<InputJob> jobs) {
    return keel::testing::error_of([&] { run(std::move(jobs)); });
  }

  fs::path root_;
};

TEST_F(CompareStageTest, LaterSurveyRegisteredAndItsNewSlabSignificant) {
  const std::vector<Eigen::Vector3f> a = scene(1, false);
  std::vector<Eigen::Vector3f> b = scene(2, true);
  Pose3 T_b_a = Pose3::Identity();
  T_b_a.linear() =
      Eigen::AngleAxisd(0.01, Eigen::Vector3d(0.3, 0.1, 1).normalized()).toRotationMatrix();
  T_b_a.translation() = Eigen::Vector3d(0.05, -0.04, 0.02);
  for (auto& p : b) p = (T_b_a * p.cast<double>()).cast<float>();
  // A few points of B far from A: their change is undefined (A has none in the cylinder).
  for (int i = 0; i < 6; ++i) b.push_back(Eigen::Vector3f(20.0f + 0.01f * i, 20.0f, 1.0f));
  const StageResult result = run({map_job("a", a), map_job("b", b)});

  const json& r = result.report;
  EXPECT_EQ(r["kind"], "maps");
  const json& reg = r["maps"]["registration"];
  const double t = reg["T_a_b"]["translation_norm_m"].get<double>();
  EXPECT_NEAR(t, T_b_a.inverse().translation().norm(), 0.005);
  EXPECT_NEAR(reg["T_a_b"]["rotation_deg"].get<double>(), 0.01 * 180 / M_PI, 0.05);
  const json& m = r["maps"]["maps"][kCombinedMapName];
  // The slab's top (1.5 m x 1 m) is significant, and a ring around its 5 m edge where the
  // 0.2 m cylinders and the 0.5 m normal neighbourhood straddle it.
  const double area = m["significant_area_m2"].get<double>();
  EXPECT_GT(area, 1.2);
  EXPECT_LT(area, 3.5);
  EXPECT_EQ(m["points_b"].get<size_t>(), b.size());

  // Per point: the slab's top rises 10 cm and is significant.
  const io::DracoPointCloud change = io::decode_draco_point_cloud(
      io::read_draco_file(root_ / "out" / change_draco_file(kCombinedMapName)));
  std::map<std::string, const std::vector<float>*> field;
  for (const auto& f : change.fields) field[f.name] = &f.values;
  ASSERT_TRUE(field.count("m3c2_m") && field.count("significant") && field.count("c2c_m") &&
              field.count("lod95_m"));
  size_t top = 0, top_significant = 0;
  for (size_t i = 0; i < change.positions.size(); ++i) {
    const Eigen::Vector3f& p = change.positions[i];
    if (p.x() > 5.2f && p.x() < 6.3f && p.y() > 3.7f && p.y() < 4.3f && p.z() > 0.05f) {
      ++top;
      top_significant += (*field["significant"])[i] == 1.0f;
      EXPECT_NEAR((*field["m3c2_m"])[i], 0.1f, 0.01f);
    }
  }
  EXPECT_GT(top, 500u);
  EXPECT_EQ(top_significant, top);
  // Farther than 0.4 m from the slab nothing changed: at most 1 % of those points significant.
  size_t far = 0, far_significant = 0;
  for (size_t i = 0; i < change.positions.size(); ++i) {
    const Eigen::Vector3f& p = change.positions[i];
    if (p.x() > 4.6f && p.x() < 6.9f && p.y() > 3.1f && p.y() < 4.9f) continue;
    ++far;
    far_significant += (*field["significant"])[i] == 1.0f;
  }
  EXPECT_LT(double(far_significant), 0.01 * far);
  EXPECT_TRUE(fs::exists(root_ / "out" / kChangesFile));

  // The sidecar: the decoded file's count and each attribute's range (brute force).
  const std::string sidecar_name = sidecar_file(change_draco_file(kCombinedMapName));
  EXPECT_NE(std::find(result.artifacts.begin(), result.artifacts.end(), sidecar_name),
            result.artifacts.end());
  const json sidecar = json::parse(std::ifstream(root_ / "out" / sidecar_name));
  EXPECT_EQ(sidecar["frame"], "world");
  EXPECT_EQ(sidecar["points"].get<size_t>(), change.positions.size());
  // Where the change is undefined (significant -1) m3c2_m and lod95_m hold their no_data,
  // below every defined value; the ranges leave it out.
  size_t undefined = 0;
  for (size_t i = 0; i < change.positions.size(); ++i) {
    if ((*field["significant"])[i] != -1.0f) continue;
    ++undefined;
    for (const char* name : {"m3c2_m", "lod95_m"})
      EXPECT_EQ((*field[name])[i], sidecar["attributes"][name]["no_data"].get<float>()) << name;
  }
  EXPECT_GE(undefined, 6u) << "the points far from A";
  for (const char* name : {"significant", "c2c_m"})
    EXPECT_FALSE(sidecar["attributes"][name].contains("no_data")) << name;
  for (const char* name : {"m3c2_m", "lod95_m", "significant", "c2c_m"}) {
    const double no_data = sidecar["attributes"][name].value("no_data", std::nan(""));
    float lo = std::numeric_limits<float>::infinity(), hi = -lo;
    for (float v : *field[name])
      if (double(v) != double(float(no_data))) lo = std::min(lo, v), hi = std::max(hi, v);
    EXPECT_EQ(sidecar["attributes"][name]["min"].get<double>(), double(lo)) << name;
    EXPECT_EQ(sidecar["attributes"][name]["max"].get<double>(), double(hi)) << name;
    if (!std::isnan(no_data)) {
      EXPECT_LT(no_data, double(lo)) << name;
    }
  }
}

// A reprocess job made with "compare": true runs its stages, then compare with options.compare
// naming job_a alone: B is the job itself, its products in its own work folder and its report
// the sections of its earlier stages.
TEST_F(CompareStageTest, AReprocessJobComparesTheJobItReprocessesWithItself) {
  const InputJob a = map_job("a", scene(1, false), {{"options", {{"map", {{"radius_m", 0.25}}}}}});
  StageContext context;
  context.work_dir = root_ / "out";
  fs::create_directories(context.work_dir);
  const std::vector<Eigen::Vector3f> b = scene(2, true);
  io::write_draco_file(context.work_dir / map_draco_file(kCombinedMapName),
                       io::encode_draco_point_cloud(b, {}, {18, 12, 5}).bytes);
  context.reports = {{"map", {{"points", b.size()}, {"radius_m", 0.3}}}};
  context.job = {{"id", "j_new"},
                 {"state", "running"},
                 {"project", "p1"},
                 {"mission_id", "m_a"},
                 {"options", {{"map", {{"radius_m", 0.3}}}, {"compare", {{"job_a", "a"}}}}}};
  context.options = {{"job_a", "a"}};
  context.input_jobs = {a};
  const StageResult result = make_compare_stage()->run(context);
  const json& r = result.report;
  EXPECT_EQ(r["job_a"], "a");
  EXPECT_EQ(r["job_b"], "j_new");
  EXPECT_EQ(r["kind"], "maps");
  const json& m = r["maps"]["maps"][kCombinedMapName];
  EXPECT_EQ(m["points_b"].get<size_t>(), b.size());
  EXPECT_GT(m["significant_area_m2"].get<double>(), 1.2);  // the new slab, as between two jobs
  // Runs: the same mission, the option that differs, and the earlier stages' figures.
  EXPECT_TRUE(r["runs"]["same_mission"].get<bool>());
  bool radius_differs = false;
  for (const json& d : r["runs"]["options_differ"])
    radius_differs |= d["option"] == "map.radius_m" && d["a"] == 0.25 && d["b"] == 0.3;
  EXPECT_TRUE(radius_differs) << r["runs"]["options_differ"].dump();
  bool points_compared = false;
  for (const json& f : r["runs"]["figures"])
    points_compared |= f["figure"] == "map.points" && f["b"].get<double>() == double(b.size());
  EXPECT_TRUE(points_compared);
}

// report.html of a compare job: its section (registration, per-map table, histogram, runs)
// passes report_html_check.py: every figure shown equals report.json's, nothing to fetch or run.
TEST_F(CompareStageTest, TheReportPageShowsTheComparison) {
  if (!fs::exists("/usr/bin/python3")) GTEST_SKIP() << "no /usr/bin/python3 for the page check";
  const StageResult result =
      run({map_job("a", scene(1, false), {{"options", {{"map", {{"x", 1}}}}}}),
           map_job("b", scene(2, true), {{"options", {{"map", {{"x", 2}}}}}})});
  ReportInput in;
  in.job = {{"id", "j_compare"}, {"stages", {"compare"}}};
  in.stage_order = {"compare"};
  in.stages = {{"compare", result.report}};
  in.stage_seconds = {{"compare", 1.5}};
  const fs::path dir = root_ / "page";
  fs::create_directories(dir);
  write_report_files(dir, build_report(in));
  const std::string command =
      "/usr/bin/python3 " KEEL_SOURCE_DIR "/tests/worker/pipeline/report_html_check.py '" +
      (dir / "report.json").string() + "' '" + (dir / "report.html").string() +
      "' --expect-id stage-compare --expect-id compare-registration --expect-id "
      "compare-maps-table --expect-id compare-options --expect-id compare-figures "
      "--expect /stages/compare/maps/maps/combined/significant_area_m2 "
      "--expect /stages/compare/maps/registration/T_a_b/translation_norm_m "
      "--expect /stages/compare/runs/options_differ/0/b";
  EXPECT_EQ(WEXITSTATUS(std::system(command.c_str())), 0) << command;
}

TEST_F(CompareStageTest, AJobWithItselfGivesZeroChange) {
  const InputJob a = map_job("a", scene(3, false));
  const StageResult result = run({a, a});
  const json& m = result.report["maps"]["maps"][kCombinedMapName];
  EXPECT_EQ(m["significant_area_m2"].get<double>(), 0.0);
  EXPECT_EQ(m["m3c2_m"]["max"].get<double>(), 0.0);
  EXPECT_EQ(m["m3c2_m"]["min"].get<double>(), 0.0);
  EXPECT_EQ(m["c2c_m"]["max"].get<double>(), 0.0);
  EXPECT_LT(result.report["maps"]["registration"]["T_a_b"]["translation_norm_m"].get<double>(),
            1e-3);
  EXPECT_EQ(result.report["runs"]["figures_that_differ"].get<size_t>(), 0u);
}

TEST_F(CompareStageTest, RefusesMapAgainstHullOtherProjectsAndUnfinishedJobs) {
  const InputJob a = map_job("a", scene(4, false));
  InputJob hull;
  hull.dir = root_ / "hull";
  fs::create_directories(hull.dir);
  TriangleMesh mesh;
  mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.faces = {{0, 1, 2}};
  io::write_draco_file(hull.dir / kRemeshedDracoFile,
                       io::encode_draco_mesh(mesh, {{"deviation", {0, 0, 0}}}).bytes);
  std::ofstream(hull.dir / kShapesFile) << R"({"shapes": []})";
  std::ofstream(hull.dir / kBaSolutionFile) << ba_solution_to_json(BaSolution{}).dump();
  write_report(hull.dir, {{"inspect", {{"tau_m", 0.02}}}});
  hull.job = {{"id", "j_hull"}, {"state", "succeeded"}, {"project", "p1"}, {"mission_id", "m2"}};

  std::string why = refusal({a, hull});
  EXPECT_NE(why.find("a map compares with a map, a hull with a hull"), std::string::npos) << why;
  EXPECT_NE(why.find("job j_hull a remeshed hull"), std::string::npos) << why;

  InputJob other = map_job("b", scene(5, false), {{"project", "p2"}});
  why = refusal({a, other});
  EXPECT_NE(why.find("only jobs of one project"), std::string::npos) << why;

  InputJob running = map_job("c", scene(6, false), {{"state", "running"}});
  why = refusal({a, running});
  EXPECT_NE(why.find("job c is running"), std::string::npos) << why;

  why = refusal({a});
  EXPECT_NE(why.find("two finished jobs"), std::string::npos) << why;
  EXPECT_THROW(run({a, a}, {{"projection_scale_m", -1}}), proto::ContractError);
  EXPECT_THROW(run({a, a}, {{"no_such_option", 1}}), proto::ContractError);
  EXPECT_THROW(run({a, a}, {{"draco_compression_level", 11}}), proto::ContractError);
}

TEST_F(CompareStageTest, HullsComparedInTheModelFrame) {
  // The same CAD triangle strip in two surveys whose x_gM differ; vertex 4 rose 5 cm more.
  auto hull_job = [&](const std::string& name, const Pose3& T_world_model, float deviation4,
                      double shape_height, double sampling_sigma) {
    InputJob job;
    job.dir = root_ / name;
    fs::create_directories(job.dir);
    TriangleMesh mesh;
    for (int i = 0; i < 6; ++i)
      mesh.vertices.push_back(T_world_model * Eigen::Vector3d(i % 3, i / 3, 0));
    mesh.faces = {{0, 1, 3}, {1, 4, 3}, {1, 2, 4}, {2, 5, 4}};
    std::vector<float> deviation(6, 0.0f);
    deviation[4] = deviation4;
    io::write_draco_file(
        job.dir / kRemeshedDracoFile,
        io::encode_draco_mesh(mesh, {{"deviation", deviation}}, {16, 14, 7}).bytes);
    const Eigen::Vector3d c = T_world_model * Eigen::Vector3d(1, 1, 0);
    json shapes = {{"options", {{"dbscan_eps_m", 0.1}}},
                   {"shapes",
                    {{{"id", 0},
                      {"centroid_world_m", {c.x(), c.y(), c.z()}},
                      {"extent_m", {0.3, 0.3, shape_height}},
                      {"max_deviation_m", shape_height},
                      {"height_sampling_sigma_m", sampling_sigma}}}}};
    std::ofstream(job.dir / kShapesFile) << shapes.dump();
    BaSolution solution;
    solution.T_world_model = T_world_model;
    std::ofstream(job.dir / kBaSolutionFile) << ba_solution_to_json(solution).dump();
    write_report(job.dir, {{"inspect", {{"deviation_noise_sigma_m", 0.003}}}});
    job.job = {
        {"id", name}, {"state", "succeeded"}, {"project", "p1"}, {"mission_id", "m_" + name}};
    return job;
  };
  Pose3 T_b = Pose3::Identity();
  T_b.translation() = Eigen::Vector3d(0.4, -0.2, 0.1);
  const StageResult result = run({hull_job("a", Pose3::Identity(), 0.10f, 0.10, 0.004),
                                  hull_job("b", T_b, 0.15f, 0.15, 0.012)});
  const json& h = result.report["hull"];
  EXPECT_NEAR(h["x_gM_difference"]["translation_norm_m"].get<double>(), T_b.translation().norm(),
              1e-9);
  EXPECT_LT(h["vertex_pairing_max_m"].get<double>(), 1e-3);
  EXPECT_EQ(h["kept"], 1);
  EXPECT_EQ(h["new"], 0);
  const json& row = h["shapes"][0];
  EXPECT_NEAR(row["height_growth_m"].get<double>(), 0.05, 1e-9);
  // Both surveys' deviation noise and both shapes' sampling gaps: sqrt(9 + 9 + 16 + 144) mm.
  EXPECT_NEAR(row["height_growth_sigma_m"].get<double>(), std::sqrt(178.0) * 1e-3, 1e-12);
  EXPECT_TRUE(row["significant_growth"].get<bool>());
  const io::DracoMesh change = io::decode_draco_mesh(
      io::read_draco_file(root_ / "out" / change_draco_file(kHullChangeName)));
  for (const auto& f : change.fields) {
    if (f.name != "deviation_change") continue;
    for (size_t i = 0; i < f.values.size(); ++i) {
      EXPECT_NEAR(f.values[i],
                  change.mesh.vertices[i].isApprox(Eigen::Vector3d(1, 1, 0), 1e-3) ? 0.05f : 0.0f,
                  1e-3);
    }
  }
  // The sidecar (model frame): vertex count and each attribute's range from the decoded mesh.
  const json sidecar =
      json::parse(std::ifstream(root_ / "out" / sidecar_file(change_draco_file(kHullChangeName))));
  EXPECT_EQ(sidecar["frame"], "model");
  EXPECT_EQ(sidecar["kind"], "mesh");
  EXPECT_EQ(sidecar["points"].get<size_t>(), change.mesh.vertices.size());
  ASSERT_EQ(change.fields.size(), 3u);
  for (const auto& f : change.fields) {
    const auto [lo, hi] = std::minmax_element(f.values.begin(), f.values.end());
    EXPECT_EQ(sidecar["attributes"][f.name]["min"].get<double>(), double(*lo)) << f.name;
    EXPECT_EQ(sidecar["attributes"][f.name]["max"].get<double>(), double(*hi)) << f.name;
  }
}

TEST(CompareRuns, OptionsAndFiguresThatDiffer) {
  const json a = {{"map", {{"metrics_radius_m", 0.25}, {"threads", 2}}}};
  const json b = {{"map", {{"metrics_radius_m", 0.3}, {"threads", 2}}},
                  {"refine", {{"dvl", false}}}};
  const json diff = options_difference(a, b);
  ASSERT_EQ(diff.size(), 2u);
  EXPECT_EQ(diff[0]["option"], "map.metrics_radius_m");
  EXPECT_EQ(diff[0]["b"], 0.3);
  EXPECT_EQ(diff[1]["option"], "refine.dvl");
  EXPECT_TRUE(diff[1]["a"].is_null());
  std::vector<std::pair<std::string, double>> numbers;
  flatten_numbers({{"map", {{"density", {{"mean", 3.5}}}, {"hist", {1, 2}}}}}, "", &numbers);
  ASSERT_EQ(numbers.size(), 1u);
  EXPECT_EQ(numbers[0].first, "map.density.mean");
}

}  // namespace
}  // namespace keel::pipeline
