// C2C against CloudCompare 2.11 (Debian's `cloudcompare`): per-point distances of a real cloud
// pair, the even and the odd rings of one Velodyne VLP-16 sweep (shared/data), equal within
// 1e-6 m. Skips, saying why, when CloudCompare or the data is absent.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "worker/compare/c2c_distance.h"
#include "worker/io/cloud/scan_file.h"

namespace keel::compare {
namespace {

namespace fs = std::filesystem;

bool on_path(const std::string& program) {
  return std::system(("command -v " + program + " >/dev/null 2>&1").c_str()) == 0;
}

void write_xyz(const fs::path& path, const std::vector<Eigen::Vector3f>& points) {
  std::ofstream out(path);
  char line[128];
  for (const auto& p : points) {
    std::snprintf(line, sizeof(line), "%.9g %.9g %.9g\n", p.x(), p.y(), p.z());
    out << line;
  }
}

TEST(CloudCompareC2c, PerPointDistancesEqualWithinAMicrometre) {
  const fs::path scan = fs::path(KEEL_SHARED_DIR) / "data" / "test_scan_vlp16.pcd";
  if (!fs::exists(scan)) GTEST_SKIP() << scan << " absent";
  if (!on_path("CloudCompare")) GTEST_SKIP() << "CloudCompare not installed (Debian: cloudcompare)";
  const PointCloud cloud = io::read_scan_file(scan, 0, {});
  ASSERT_TRUE(cloud.has_ring());
  std::vector<Eigen::Vector3f> reference, compared;
  for (size_t i = 0; i < cloud.size(); ++i)
    (cloud.ring[i] % 2 == 0 ? reference : compared).push_back(cloud.xyz[i]);
  ASSERT_GT(reference.size(), 5000u);
  ASSERT_GT(compared.size(), 5000u);

  const fs::path dir = fs::temp_directory_path() / ("keel_cc_c2c_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  write_xyz(dir / "compared.xyz", compared);
  write_xyz(dir / "reference.xyz", reference);
  // The first cloud opened is the compared one, the second the reference.
  const std::string command = "cd '" + dir.string() +
                              "' && QT_QPA_PLATFORM=offscreen timeout 120 CloudCompare -SILENT "
                              "-NO_TIMESTAMP -C_EXPORT_FMT ASC -PREC 12 -O compared.xyz -O "
                              "reference.xyz -C2C_DIST -SAVE_CLOUDS FILE \"out_compared.asc "
                              "out_reference.asc\" > cloudcompare.log 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << "see " << dir / "cloudcompare.log";

  std::ifstream in(dir / "out_compared.asc");
  ASSERT_TRUE(in) << "CloudCompare wrote no out_compared.asc";
  std::vector<double> theirs;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    double x, y, z, d;
    ASSERT_TRUE(fields >> x >> y >> z >> d) << line;
    theirs.push_back(d);
  }
  ASSERT_EQ(theirs.size(), compared.size());
  const NearestIndex index(reference);
  const std::vector<float> ours = c2c_distances(index, compared, 2);
  double worst = 0.0;
  for (size_t i = 0; i < ours.size(); ++i) worst = std::max(worst, std::abs(ours[i] - theirs[i]));
  EXPECT_LE(worst, 1e-6);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace keel::compare
