// `keel-worker filter` and `keel-worker metrics` as programs: PCL's published bun0 answers
// for the filter chain, and a planar grid whose metrics have closed forms (planarity 1,
// roughness 0, density = the grid points within r, counted by brute force, / (pi r^2)).
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <Eigen/Geometry>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "tests/worker/main/worker_program_fixture.h"
#include "worker/io/cloud/scan_file.h"

namespace {

namespace fs = std::filesystem;

using Output = keel::testing::ProgramOutput;
using keel::testing::read_file;

class MapToolsTest : public keel::testing::WorkerProgramTest {
 protected:
};

fs::path bun0() { return fs::path(KEEL_SHARED_DIR) / "data" / "bun0.pcd"; }

TEST_F(MapToolsTest, FilterReproducesPclBun0Answers) {
  if (!fs::exists(bun0())) GTEST_SKIP() << bun0() << " absent (…/shared absent)";
  const Output voxel = run({"filter", "--in", bun0().string(), "--out", (dir_ / "v.pcd").string(),
                            "--chain", R"([{"type":"voxel_grid","leaf":0.02}])", "--json"});
  ASSERT_EQ(voxel.code, 0) << voxel.err;
  const auto v = nlohmann::json::parse(voxel.out);
  EXPECT_EQ(v["points_in"], 397);
  EXPECT_EQ(v["points_out"], 103);
  EXPECT_EQ(keel::io::read_scan_file(dir_ / "v.pcd", 0).size(), 103u);

  // The chain from a file, PLY out, plain-text counts.
  std::ofstream(dir_ / "ror.json") << R"([{"type": "ror", "radius": 0.02, "min_neighbors": 14}])";
  const Output ror = run({"filter", "--in", bun0().string(), "--out", (dir_ / "r.ply").string(),
                          "--chain", (dir_ / "ror.json").string()});
  ASSERT_EQ(ror.code, 0) << ror.err;
  EXPECT_NE(ror.out.find("ror: 397 -> 307"), std::string::npos) << ror.out;
  EXPECT_NE(ror.out.find("in 397 points, out 307 points"), std::string::npos) << ror.out;
  EXPECT_EQ(keel::io::read_scan_file(dir_ / "r.ply", 0).size(), 307u);
}

TEST_F(MapToolsTest, FilterErrorsNameTheProblem) {
  if (!fs::exists(bun0())) GTEST_SKIP() << bun0() << " absent (…/shared absent)";
  const Output bad = run({"filter", "--in", bun0().string(), "--out", (dir_ / "x.pcd").string(),
                          "--chain", R"([{"type":"voxel_grid","leaf":-1}])"});
  EXPECT_EQ(bad.code, 1);
  EXPECT_NE(bad.err.find("--chain[0].leaf"), std::string::npos) << bad.err;
  const Output missing = run({"filter", "--in", (dir_ / "nope.pcd").string(), "--out",
                              (dir_ / "x.pcd").string(), "--chain", "[]"});
  EXPECT_EQ(missing.code, 1);
  EXPECT_NE(missing.err.find("nope.pcd"), std::string::npos) << missing.err;
  const Output help = run({"filter", "--help"});
  EXPECT_EQ(help.code, 0);
  EXPECT_NE(help.out.find("crop_box"), std::string::npos) << help.out;
  EXPECT_NE(help.out.find("dror"), std::string::npos) << help.out;
}

TEST_F(MapToolsTest, MetricsOfAPlaneHaveClosedForms) {
  // A tilted planar grid, 2.7 m x 2.7 m at 4.5 cm spacing (r / spacing is not a whole
  // number, so no grid point lies on a neighbourhood's boundary).
  const double spacing = 0.045, radius = 0.25;
  const int n = 61;
  const Eigen::Matrix3f R =
      Eigen::AngleAxisf(0.4f, Eigen::Vector3f(1.0f, 2.0f, 0.5f).normalized()).toRotationMatrix();
  keel::PointCloud plane;
  std::vector<Eigen::Vector2d> grid;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      grid.emplace_back(i * spacing, j * spacing);
      plane.xyz.push_back(R * Eigen::Vector3f(i * spacing, j * spacing, 0.0f) +
                          Eigen::Vector3f(10.0f, -4.0f, 2.0f));
    }
  keel::io::write_scan_file(dir_ / "plane.ply", plane);
  const Output out = run({"metrics", "--in", (dir_ / "plane.ply").string(), "--radius", "0.25",
                          "--out", (dir_ / "per_point.txt").string(), "--json"});
  ASSERT_EQ(out.code, 0) << out.err;
  const auto summary = nlohmann::json::parse(out.out);
  EXPECT_EQ(summary["points"], n * n);
  EXPECT_NEAR(summary["planarity"]["median"].get<double>(), 1.0, 0.02) << out.out;
  // Edge points see half-discs (l2 < l1), so the mean is below 1; interior ones are checked
  // exactly below.
  EXPECT_GT(summary["planarity"]["mean"].get<double>(), 0.8) << out.out;
  EXPECT_LT(summary["roughness_m"]["max"].get<double>(), 1e-5) << out.out;

  // Per point: density = brute-force count within r / (pi r^2); interior planarity 1.
  std::ifstream rows(dir_ / "per_point.txt");
  std::string header;
  std::getline(rows, header);
  EXPECT_EQ(header, "# x y z density roughness planarity");
  size_t k = 0;
  double x, y, z, density, roughness, planarity;
  while (rows >> x >> y >> z >> density >> roughness >> planarity) {
    ASSERT_LT(k, grid.size());
    // Grid points exactly at distance r (5 spacings: (5,0), (3,4), ...) are within float
    // rounding of the boundary and may count either way.
    size_t strictly_inside = 0, inside_or_on = 0;
    for (const auto& g : grid) {
      const double d = (g - grid[k]).norm();
      if (d < radius - 1e-6) ++strictly_inside;
      if (d <= radius + 1e-6) ++inside_or_on;
    }
    const double count = density * M_PI * radius * radius;
    EXPECT_GE(count, strictly_inside - 1e-3) << k;
    EXPECT_LE(count, inside_or_on + 1e-3) << k;
    const double side = (n - 1) * spacing;
    const bool interior = grid[k].minCoeff() >= radius && grid[k].maxCoeff() <= side - radius;
    if (interior) EXPECT_NEAR(planarity, 1.0, 1e-3) << k;
    ++k;
  }
  EXPECT_EQ(k, static_cast<size_t>(n * n));

  // PLY output carries the three scalar fields.
  const Output ply = run({"metrics", "--in", (dir_ / "plane.ply").string(), "--out",
                          (dir_ / "per_point.ply").string()});
  ASSERT_EQ(ply.code, 0) << ply.err;
  EXPECT_NE(ply.out.find("planarity       mean"), std::string::npos) << ply.out;
  const std::string ply_text = read_file(dir_ / "per_point.ply");
  for (const char* field : {"density", "roughness", "planarity"})
    EXPECT_NE(ply_text.find(std::string("property float ") + field), std::string::npos) << field;
  const Output bad = run({"metrics", "--in", (dir_ / "plane.ply").string(), "--out",
                          (dir_ / "per_point.csv").string()});
  EXPECT_EQ(bad.code, 1);
  EXPECT_NE(bad.err.find(".ply or .txt"), std::string::npos) << bad.err;
}

}  // namespace
