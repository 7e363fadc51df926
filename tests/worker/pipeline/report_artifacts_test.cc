// The job's viewer artifacts and report.html on real stage reports of keel-sim missions:
// usv-bridge through ingest, refine and map; hauv-hull through ingest, refine, ba and inspect.
//   - report.html passes report_html_check.py (XML and HTML parse with Debian's Python: every
//     figure of report.json present with its exact value, nothing to fetch or run) and its
//     stage sections show Table II, Table V, the BA figures and the shapes;
//   - trajectories.json: the root mean square of each estimate's per-pose ATE is the report's
//     ATE RMSE; `refined` is trajectory_refined.tum; `ba` in the model frame moved by
//     T_world_model is trajectory_ba.tum;
//   - every sidecar against a brute-force scan of its decoded Draco file (counts, box, each
//     attribute's range), the combined map's `sensor` counts against the sensor maps;
//   - previews: the expected count, each point one of the map's (its PLY) within the
//     quantization bounds, used once, and spread evenly (binomial bound per 2 m cell);
//   - per-point density (Eq. 23) against a brute-force neighbour count on the PLY map at the
//     decoded point's original, so the attribute travels with its point through Draco;
//   - cad_model.drc decodes to the mission's CAD mesh within the quantization bound.
// Heavy (label `heavy`, about a minute): two simulations and six stages.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <unordered_map>

#include "tests/worker/pipeline/sim_mission.h"
#include "worker/io/cloud/scan_file.h"
#include "worker/io/draco/draco_codec.h"
#include "worker/io/mesh/mesh_reader.h"
#include "worker/io/mission.h"
#include "worker/io/tum.h"
#include "worker/pipeline/job_runner.h"
#include "worker/pipeline/pose_json.h"
#include "worker/pipeline/report.h"
#include "worker/pipeline/trajectories_file.h"
#include "worker/stages/ba/stage.h"
#include "worker/stages/map/stage.h"
#include "worker/stages/refine/stage.h"

namespace keel::pipeline {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

fs::path temp_root() {
  return fs::temp_directory_path() / ("keel_report_artifacts_" + std::to_string(getpid()));
}

json read_json(const fs::path& path) {
  std::ifstream in(path);
  return json::parse(in);
}

// Runs the stages as `keel-worker run` does and writes report.json and report.html.
json run_job(const fs::path& mission, const std::vector<std::string>& stages, const json& options,
             const fs::path& work) {
  JobSpec spec;
  spec.mission_dir = mission;
  spec.work_dir = work;
  spec.stages = stages;
  spec.options = options;
  const JobResult result = JobRunner().run(spec);
  EXPECT_EQ(result.outcome, JobOutcome::kSucceeded) << result.error;
  ReportInput input;
  input.job = {{"id", "local"}, {"stages", stages}, {"options", options}};
  input.mission = {{"name", mission.filename().string()}};
  input.stage_order = stages;
  input.stages = result.reports;
  input.stage_seconds = result.stage_seconds;
  write_report_files(work, build_report(input));
  return read_json(work / kReportFileName);
}

void expect_report_html_passes(const fs::path& work, const std::vector<std::string>& pointers,
                               const std::vector<std::string>& ids) {
  if (!fs::exists("/usr/bin/python3")) GTEST_SKIP() << "no /usr/bin/python3";
  std::string command =
      "/usr/bin/python3 " KEEL_SOURCE_DIR "/tests/worker/pipeline/report_html_check.py '" +
      (work / "report.json").string() + "' '" + (work / "report.html").string() + "'";
  for (const auto& p : pointers) command += " --expect '" + p + "'";
  for (const auto& id : ids) command += " --expect-id '" + id + "'";
  EXPECT_EQ(WEXITSTATUS(std::system(command.c_str())), 0) << command;
}

// trajectories.json's per-pose ATE against the report's Table II.
void expect_ate_matches_report(const json& trajectories, const json& table) {
  const std::map<std::string, std::string> rows = {{"recorded", "map"},
                                                   {"refined", "refined_with_dvl"},
                                                   {"refined_no_dvl", "refined_without_dvl"}};
  for (const auto& t : trajectories["trajectories"]) {
    const auto row = rows.find(t["name"].get<std::string>());
    if (row == rows.end()) continue;
    SCOPED_TRACE(row->first);
    ASSERT_TRUE(t.contains("ate_m"));
    ASSERT_EQ(t["ate_m"].size(), t["t"].size());
    double sum = 0;
    size_t count = 0;
    for (const auto& e : t["ate_m"])
      if (e.is_number()) sum += e.get<double>() * e.get<double>(), ++count;
    const json& ate = table[row->second]["ate"]["translation_m"];
    EXPECT_EQ(count, ate["count"].get<size_t>());
    EXPECT_NEAR(std::sqrt(sum / count), ate["rmse"].get<double>(), 1e-12);
  }
}

// A sidecar against its decoded Draco point cloud: counts, box and every attribute's range.
io::DracoPointCloud expect_sidecar_matches(const fs::path& work, const std::string& drc) {
  SCOPED_TRACE(drc);
  const json sidecar = read_json(work / (fs::path(drc).stem().string() + ".json"));
  const io::DracoPointCloud cloud =
      io::decode_draco_point_cloud(io::read_draco_file(work / drc), drc);
  EXPECT_EQ(sidecar["file"], drc);
  EXPECT_EQ(sidecar["kind"], "point_cloud");
  EXPECT_EQ(sidecar["frame"], "world");
  EXPECT_EQ(sidecar["points"].get<size_t>(), cloud.positions.size());
  Eigen::Vector3f lo = cloud.positions.front(), hi = lo;
  for (const auto& p : cloud.positions) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(sidecar["bbox_min"][c].get<double>(), lo[c]);
    EXPECT_EQ(sidecar["bbox_max"][c].get<double>(), hi[c]);
  }
  EXPECT_EQ(sidecar["attributes"].size(), cloud.fields.size());
  for (const auto& field : cloud.fields) {
    SCOPED_TRACE(field.name);
    if (!sidecar["attributes"].contains(field.name)) {
      ADD_FAILURE() << "not in the sidecar";
      continue;
    }
    const json& a = sidecar["attributes"][field.name];
    const bool has_no_data = a.contains("no_data");
    const float no_data = has_no_data ? a["no_data"].get<float>() : 0.f;
    float min = INFINITY, max = -INFINITY;
    for (float v : field.values)
      if (!has_no_data || v != no_data) min = std::min(min, v), max = std::max(max, v);
    EXPECT_EQ(a["min"].get<double>(), min);
    EXPECT_EQ(a["max"].get<double>(), max);
  }
  return cloud;
}

const io::ScalarField* field_of(const io::DracoPointCloud& cloud, const std::string& name) {
  for (const auto& f : cloud.fields)
    if (f.name == name) return &f;
  return nullptr;
}

// Points of a map bucketed in cubes of `cell_m`, for nearest-point and radius queries.
class Buckets {
 public:
  Buckets(const std::vector<Eigen::Vector3f>& points, double cell_m)
      : points_(points), cell_m_(cell_m) {
    for (size_t i = 0; i < points.size(); ++i) cells_[key(cell(points[i]))].push_back(i);
  }
  // Indices of the points within `radius` (<= cell_m) of p.
  std::vector<size_t> within(const Eigen::Vector3f& p, double radius) const {
    std::vector<size_t> out;
    const Eigen::Vector3i c = cell(p);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = cells_.find(key(c + Eigen::Vector3i(dx, dy, dz)));
          if (it == cells_.end()) continue;
          for (size_t i : it->second)
            if ((points_[i] - p).cast<double>().norm() <= radius) out.push_back(i);
        }
    return out;
  }

 private:
  Eigen::Vector3i cell(const Eigen::Vector3f& p) const {
    return (p.cast<double>() / cell_m_).array().floor().cast<int>();
  }
  static int64_t key(const Eigen::Vector3i& c) {
    return (int64_t(c.x()) * 73856093) ^ (int64_t(c.y()) * 19349663) ^ (int64_t(c.z()) * 83492791);
  }
  const std::vector<Eigen::Vector3f>& points_;
  double cell_m_;
  std::unordered_map<int64_t, std::vector<size_t>> cells_;
};

class ReportArtifactsTest : public ::testing::Test {
 protected:
  // KEEL_KEEP_TEST_FILES=1 keeps the missions and work folders for a look after a failure.
  static void TearDownTestSuite() {
    if (!std::getenv("KEEL_KEEP_TEST_FILES")) fs::remove_all(temp_root());
  }
};

TEST_F(ReportArtifactsTest, BridgeRefineAndMap) {
  const fs::path mission = temp_root() / "usv-bridge";
  testing::simulate(mission, "usv-bridge", 7, 20.0, {"imu", "dvl", "lidar_h", "lidar_v", "sonar"});
  const fs::path work = temp_root() / "bridge_work";
  const size_t kPreview = 60000;
  const json options = {{"map",
                         {{"preview_max_points", kPreview},
                          {"write_point_metrics", true},
                          {"metrics_max_points", 5000}}}};
  const json report = run_job(mission, {"ingest", "refine", "map"}, options, work);
  const json& refine = report["stages"]["refine"];
  const json& map = report["stages"]["map"];

  // report.html.
  std::vector<std::string> pointers;
  for (const char* row : {"map", "refined_without_dvl", "refined_with_dvl"})
    for (const char* error : {"ate", "rpe"})
      pointers.push_back(std::string("/stages/refine/evaluation/table/") + row + "/" + error +
                         "/translation_m/rmse");
  pointers.push_back("/stages/refine/dvl/dvl_scale/value");
  pointers.push_back("/stages/refine/dvl/dvl_scale/sigma");
  pointers.push_back("/stages/refine/dvl/dvl_rotation/sigma_deg/2");
  for (size_t r = 0; r < 3; ++r)
    for (const auto& column : map["metrics"]["table_v"]["columns"])
      pointers.push_back("/stages/map/metrics/table_v/rows/" + std::to_string(r) + "/" +
                         column.get<std::string>());
  pointers.push_back("/stages/map/metrics/maps/slam_map/roughness_m/median");
  pointers.push_back("/stages/map/combined/points");
  pointers.push_back("/stages/map/sensors/lidar_h/stats/final_stage/filters/0/points_out");
  expect_report_html_passes(work, pointers,
                            {"refine-table-ii", "refine-ate-over-time", "map-table-v",
                             "map-distribution-roughness", "map-points", "map-filters-lidar_h"});

  // trajectories.json.
  const json trajectories = read_json(work / kTrajectoriesFile);
  expect_ate_matches_report(trajectories, refine["evaluation"]["table"]);
  const Trajectory refined = io::read_tum(work / kRefinedTrajectoryFile);
  for (const auto& t : trajectories["trajectories"]) {
    if (t["name"] != "refined") continue;
    ASSERT_EQ(t["t"].size(), refined.size());
    for (size_t i = 0; i < refined.size(); ++i) {
      EXPECT_EQ(t["t"][i].get<double>(), ns_to_seconds(refined[i].t_ns));
      for (int c = 0; c < 3; ++c)
        EXPECT_EQ(t["xyz"][i][c].get<double>(), refined[i].T_world_body.translation()[c]);
    }
  }

  // Sidecars of every map and preview; the combined map's sensors.
  std::vector<std::string> sensors;
  std::map<std::string, size_t> points;
  for (const auto& item : map["sensors"].items()) {
    sensors.push_back(item.key());
    points[item.key()] = expect_sidecar_matches(work, map_draco_file(item.key())).positions.size();
  }
  const io::DracoPointCloud combined = expect_sidecar_matches(work, map_draco_file("combined"));
  const json combined_sidecar = read_json(work / "map_combined.json");
  EXPECT_EQ(combined_sidecar["attributes"]["sensor"]["labels"], json(sensors));
  const io::ScalarField* sensor = field_of(combined, "sensor");
  ASSERT_NE(sensor, nullptr);
  std::vector<size_t> per_label(sensors.size(), 0);
  for (float v : sensor->values) ++per_label[static_cast<size_t>(v)];
  for (size_t k = 0; k < sensors.size(); ++k) EXPECT_EQ(per_label[k], points[sensors[k]]);
  for (const char* metric : {"density", "roughness", "planarity"})
    EXPECT_NE(field_of(combined, metric), nullptr) << metric;

  // Previews: lidar_h (535k points) and combined have one, sonar (27k) none.
  EXPECT_FALSE(fs::exists(work / "map_sonar_preview.drc"));
  EXPECT_FALSE(read_json(work / "map_sonar.json").contains("preview"));
  for (const std::string name : {"lidar_h", "combined"}) {
    SCOPED_TRACE(name);
    const std::string file = "map_" + name + "_preview.drc";
    const json entry = read_json(work / ("map_" + name + ".json"))["preview"];
    EXPECT_EQ(entry, (json{{"file", file}, {"points", kPreview}}));
    const io::DracoPointCloud preview = expect_sidecar_matches(work, file);
    ASSERT_EQ(preview.positions.size(), kPreview);
    const PointCloud original = io::read_scan_file(work / map_ply_file(name), 0);
    // The preview's own quantization, on a box no larger than the combined map's.
    const double bound = map["combined"]["draco"]["position_error_bound_m"].get<double>() + 1e-6;
    const Buckets buckets(original.xyz, 0.01);
    std::vector<bool> used(original.size(), false);
    size_t unmatched = 0, reused = 0;
    std::map<std::tuple<int, int, int>, std::pair<double, double>> cells;  // map, preview counts
    auto cell_of = [](const Eigen::Vector3f& p) {
      return std::make_tuple(int(std::floor(p.x() / 2)), int(std::floor(p.y() / 2)),
                             int(std::floor(p.z() / 2)));
    };
    for (const auto& p : original.xyz) cells[cell_of(p)].first += 1;
    for (const auto& p : preview.positions) {
      const std::vector<size_t> near = buckets.within(p, bound);
      size_t best = near.size() == 1 ? near[0] : SIZE_MAX;
      for (size_t i : near)  // several originals within the bound: the nearest unused one
        if (!used[i] &&
            (best == SIZE_MAX || (original.xyz[i] - p).norm() < (original.xyz[best] - p).norm()))
          best = i;
      if (best == SIZE_MAX) {
        ++unmatched;
        continue;
      }
      reused += used[best];
      used[best] = true;
      cells[cell_of(original.xyz[best])].second += 1;
    }
    EXPECT_EQ(unmatched, 0u);
    EXPECT_EQ(reused, 0u);
    const double share = static_cast<double>(kPreview) / original.size();
    for (const auto& [cell, counts] : cells)
      EXPECT_NEAR(counts.second, counts.first * share,
                  4.0 * std::sqrt(counts.first * share * (1 - share)) + 1.0);
  }

  // Per-point density (Eq. 23) of lidar_v at its decoded points' originals, brute force.
  const io::DracoPointCloud lidar_v =
      io::decode_draco_point_cloud(io::read_draco_file(work / map_draco_file("lidar_v")));
  const PointCloud original = io::read_scan_file(work / map_ply_file("lidar_v"), 0);
  const io::ScalarField* density = field_of(lidar_v, "density");
  ASSERT_NE(density, nullptr);
  const json sidecar = read_json(work / "map_lidar_v.json");
  const json& range = sidecar["attributes"]["density"];
  const double step = (range["max"].get<double>() - range["no_data"].get<double>()) / 4095;
  const double r = map["metrics"]["radius_m"].get<double>();
  const Buckets coarse(original.xyz, r);
  const Buckets fine(original.xyz, 0.005);
  for (size_t k = 0; k < lidar_v.positions.size(); k += lidar_v.positions.size() / 150) {
    const Eigen::Vector3f& q = lidar_v.positions[k];
    const std::vector<size_t> self = fine.within(q, 1e-3);
    ASSERT_FALSE(self.empty()) << k;
    size_t nearest = self[0];
    for (size_t i : self)
      if ((original.xyz[i] - q).norm() < (original.xyz[nearest] - q).norm()) nearest = i;
    const Eigen::Vector3f& p = original.xyz[nearest];
    const double expected = coarse.within(p, r).size() / (M_PI * r * r);
    EXPECT_NEAR(density->values[k], expected, step + 1e-3 * expected) << k;
  }
}

TEST_F(ReportArtifactsTest, HullBaAndInspect) {
  const fs::path mission = temp_root() / "hauv-hull";
  testing::simulate(mission, "hauv-hull", 3, 20.0);
  const fs::path work = temp_root() / "hull_work";
  const json report = run_job(mission, {"ingest", "refine", "ba", "inspect"},
                              {{"ba", {{"tracks", "ground_truth"}}}}, work);
  const json& ba = report["stages"]["ba"];
  const json& inspect = report["stages"]["inspect"];

  std::vector<std::string> pointers;
  for (const auto& item : ba["modes"].items()) {
    const std::string mode = "/stages/ba/modes/" + item.key();
    pointers.push_back(mode + "/iterations");
    pointers.push_back(mode + "/final_cost");
    pointers.push_back(mode + "/dvl_residuals_final/sigma_m");
    pointers.push_back(mode + "/dvl_residuals_gicp/percentiles_m/p95");
  }
  pointers.push_back("/stages/ba/modes/proposed/T_world_model_vs_truth/translation_error_m");
  ASSERT_FALSE(inspect["shapes"].empty());
  pointers.push_back("/stages/inspect/shapes/0/height_m");
  pointers.push_back("/stages/inspect/shapes/0/extent_m/0");
  pointers.push_back("/stages/inspect/shapes/0/centroid_world/2");
  pointers.push_back("/stages/inspect/shapes/0/views");
  pointers.push_back("/stages/inspect/truth/found");
  pointers.push_back("/stages/inspect/truth/missed");
  expect_report_html_passes(work, pointers,
                            {"ba-modes", "ba-iterations", "ba-residuals", "ba-dvl-residuals",
                             "inspect-shapes", "inspect-truth", "refine-table-ii"});

  // trajectories.json: refine's entries kept, ba's in the model frame.
  const json trajectories = read_json(work / kTrajectoriesFile);
  expect_ate_matches_report(trajectories, report["stages"]["refine"]["evaluation"]["table"]);
  const Pose3 T_world_model = pose_from_json(trajectories["T_world_model"], "T_world_model");
  const Trajectory ba_world = io::read_tum(work / kBaTrajectoryFile);
  bool found = false;
  for (const auto& t : trajectories["trajectories"]) {
    if (t["name"] != "ba") continue;
    found = true;
    EXPECT_EQ(t["frame"], "model");
    ASSERT_EQ(t["xyz"].size(), ba_world.size());
    for (size_t i = 0; i < ba_world.size(); ++i) {
      const Eigen::Vector3d in_model(t["xyz"][i][0].get<double>(), t["xyz"][i][1].get<double>(),
                                     t["xyz"][i][2].get<double>());
      EXPECT_LT((T_world_model * in_model - ba_world[i].T_world_body.translation()).norm(), 1e-9);
    }
  }
  EXPECT_TRUE(found);

  // cad_model.drc: the mission's CAD mesh, model frame, within the quantization bound.
  const TriangleMesh cad = io::read_mesh(io::load_mission(mission).cad_mesh_path);
  const io::DracoMesh decoded = io::decode_draco_mesh(io::read_draco_file(work / kCadModelFile));
  const json cad_sidecar = read_json(work / "cad_model.json");
  EXPECT_EQ(cad_sidecar["frame"], "model");
  EXPECT_EQ(cad_sidecar["kind"], "mesh");
  EXPECT_EQ(cad_sidecar["faces"].get<size_t>(), cad.faces.size());
  EXPECT_EQ(decoded.mesh.faces.size(), cad.faces.size());
  const double bound = ba["cad_model"]["position_error_bound_m"].get<double>() + 1e-6;
  std::vector<Eigen::Vector3f> cad_points;
  for (const auto& v : cad.vertices) cad_points.push_back(v.cast<float>());
  const Buckets buckets(cad_points, 0.01);
  for (const auto& v : decoded.mesh.vertices)
    EXPECT_FALSE(buckets.within(v.cast<float>(), bound).empty()) << v.transpose();

  // mesh_remeshed.json against the decoded mesh.
  const json remeshed = read_json(work / "mesh_remeshed.json");
  const io::DracoMesh mesh = io::decode_draco_mesh(io::read_draco_file(work / "mesh_remeshed.drc"));
  EXPECT_EQ(remeshed["frame"], "world");
  EXPECT_EQ(remeshed["points"].get<size_t>(), mesh.mesh.vertices.size());
  EXPECT_EQ(remeshed["faces"].get<size_t>(), mesh.mesh.faces.size());
  ASSERT_EQ(mesh.fields.size(), 1u);
  const auto& deviation = mesh.fields[0].values;
  EXPECT_EQ(remeshed["attributes"]["deviation"]["min"].get<double>(),
            *std::min_element(deviation.begin(), deviation.end()));
  EXPECT_EQ(remeshed["attributes"]["deviation"]["max"].get<double>(),
            *std::max_element(deviation.begin(), deviation.end()));
}

}  // namespace
}  // namespace keel::pipeline
