// The map stage's extra files: the even thinning (exact count, uniform), the preview as a subset of
// the map with the expected count, spread evenly in space and with each point's sensor kept, and
// the per-point metrics against a brute-force neighbourhood count (Eq. 23) and plane fit (Eq. 24).
#include "worker/stages/map/map_outputs.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Eigenvalues>

#include <cmath>
#include <map>
#include <random>

#include "worker/io/draco/draco_codec.h"

namespace keel::pipeline {
namespace {

namespace fs = std::filesystem;

// Exactly m ascending indices, the same for the same n and m, and every stretch of the order
// keeps its share m / n within binomial noise (4 sigma).
TEST(EvenThinning, ExactlyMIndicesSpreadUniformly) {
  for (const auto& [n, m] : std::vector<std::pair<size_t, size_t>>{
           {10, 3}, {1000, 999}, {1000, 1}, {7919, 100}, {12345678, 2000000}}) {
    SCOPED_TRACE(std::to_string(n) + " -> " + std::to_string(m));
    const std::vector<size_t> kept = even_thinning(n, m);
    ASSERT_EQ(kept.size(), m);
    EXPECT_EQ(kept, even_thinning(n, m));
    for (size_t i = 0; i < m; ++i) {
      EXPECT_LT(kept[i], n);
      if (i > 0) {
        EXPECT_GT(kept[i], kept[i - 1]);
      }
    }
    const size_t blocks = 20;
    const double p = static_cast<double>(m) / n;
    std::vector<double> per_block(blocks, 0.0);
    for (size_t k : kept) per_block[k * blocks / n] += 1;
    for (size_t b = 0; b < blocks; ++b) {
      const double size = static_cast<double>((b + 1) * n / blocks - b * n / blocks);
      EXPECT_NEAR(per_block[b], size * p, 4.0 * std::sqrt(size * p * (1 - p)) + 1.0) << b;
    }
  }
  EXPECT_EQ(even_thinning(5, 5), (std::vector<size_t>{0, 1, 2, 3, 4}));
  EXPECT_EQ(even_thinning(3, 10), (std::vector<size_t>{0, 1, 2}));
}

// A "lidar" part on a 2 cm grid of a 6 m x 4 m wall, in row order, and a "sonar" part below it.
std::vector<PointCloud> wall_parts() {
  std::vector<PointCloud> parts(2);
  for (int i = 0; i < 300; ++i)
    for (int j = 0; j < 200; ++j) {
      parts[0].xyz.emplace_back(0.02f * i, 0.f, 0.02f * j);
      parts[0].intensity.push_back(static_cast<float>((i + j) % 256));
    }
  for (int i = 0; i < 150; ++i)
    for (int j = 0; j < 100; ++j) {
      parts[1].xyz.emplace_back(0.04f * i, 0.5f, -0.04f * j - 1.f);
      parts[1].intensity.push_back(7.f);
    }
  return parts;
}

TEST(MapPreview, AnEvenSubsetWithTheExpectedCountAndSensors) {
  const fs::path dir = fs::temp_directory_path() / ("keel_map_outputs_" + std::to_string(getpid()));
  fs::create_directories(dir);
  const std::vector<PointCloud> parts = wall_parts();
  const std::vector<const PointCloud*> pointers = {&parts[0], &parts[1]};
  const size_t n = parts[0].size() + parts[1].size(), m = 9000;
  io::PartsAttributes attributes;
  attributes.label_name = kSensorAttribute;
  attributes.part_labels = {"lidar", "sonar"};
  io::DracoOptions draco;
  draco.position_bits = 18;
  const PreviewOutput out =
      write_map_preview(pointers, attributes, m, draco, map_preview_file("combined"), dir);
  EXPECT_EQ(out.artifacts,
            (std::vector<std::string>{"map_combined_preview.drc", "map_combined_preview.json"}));
  EXPECT_EQ(out.report["points"], m);
  ASSERT_TRUE(fs::exists(dir / "map_combined_preview.json"));

  const io::DracoPointCloud preview =
      io::decode_draco_point_cloud(io::read_draco_file(dir / "map_combined_preview.drc"));
  ASSERT_EQ(preview.positions.size(), m);
  const io::ScalarField* sensor = nullptr;
  for (const auto& f : preview.fields)
    if (f.name == "sensor") sensor = &f;
  ASSERT_NE(sensor, nullptr);

  // Each preview point is a distinct map point (within the 18-bit quantization, 0.02 mm here)
  // of the sensor it is labelled with: map points sit on 2 cm / 4 cm grids, so the nearest grid
  // node is the only candidate.
  std::map<std::tuple<int, int, int, int>, int> used;
  std::map<std::pair<int, int>, double> map_cells, preview_cells;  // 0.5 m cells of the wall
  for (size_t k = 0; k < 2; ++k)
    for (const auto& p : parts[k].xyz)
      map_cells[{int(std::floor(p.x() / 0.5f)), int(std::floor(p.z() / 0.5f))}] += 1;
  for (size_t i = 0; i < m; ++i) {
    const Eigen::Vector3f& p = preview.positions[i];
    const int k = static_cast<int>(sensor->values[i]);
    ASSERT_TRUE(k == 0 || k == 1);
    const float step = k == 0 ? 0.02f : 0.04f;
    const Eigen::Vector3f node(
        std::round(p.x() / step) * step, k == 0 ? 0.f : 0.5f,
        k == 0 ? std::round(p.z() / step) * step : std::round((p.z() + 1.f) / step) * step - 1.f);
    EXPECT_LT((node - p).norm(), 1e-4f) << "preview point " << i << " is not a map point";
    const auto key =
        std::make_tuple(k, int(std::lround(p.x() / step)), 0, int(std::lround(p.z() / step)));
    EXPECT_EQ(used[key]++, 0) << "map point used twice";
    preview_cells[{int(std::floor(node.x() / 0.5f)), int(std::floor(node.z() / 0.5f))}] += 1;
  }
  // Evenly spread: each 0.5 m cell keeps its share m / n of its points (12 %) within binomial
  // noise (4 sigma).
  const double share = static_cast<double>(m) / n;
  for (const auto& [cell, count] : map_cells)
    EXPECT_NEAR(preview_cells[cell], count * share,
                4.0 * std::sqrt(count * share * (1 - share)) + 1.0)
        << "cell " << cell.first << "," << cell.second;
  fs::remove_all(dir);
}

TEST(MapPreview, RefusedForAMapThatNeedsNone) {
  const std::vector<PointCloud> parts = wall_parts();
  EXPECT_THROW(write_map_preview({&parts[1]}, {}, parts[1].size(), io::DracoOptions{}, "x.drc",
                                 fs::temp_directory_path()),
               std::invalid_argument);
  EXPECT_TRUE(preview_entry("lidar", 10, 10).is_null());
  EXPECT_EQ(preview_entry("lidar", 11, 10),
            (nlohmann::json{{"file", "map_lidar_preview.drc"}, {"points", 10}}));
}

// Distance of `p` to the least-squares plane of `points` (Eq. 24's roughness).
double plane_distance(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& p) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& q : points) mean += q;
  mean /= points.size();
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& q : points) cov += (q - mean) * (q - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  return std::fabs(eig.eigenvectors().col(0).dot(p - mean));
}

TEST(PointMetricFields, DensityAndRoughnessMatchABruteForceNeighbourhood) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.f, 2.f);
  std::normal_distribution<float> noise(0.f, 0.005f);
  std::vector<Eigen::Vector3f> xyz;
  for (int i = 0; i < 3000; ++i) xyz.emplace_back(u(rng), u(rng), 0.1f * u(rng) + noise(rng));
  xyz.emplace_back(10.f, 10.f, 10.f);  // alone: density 1 / (pi r^2), roughness undefined
  mapping::MapMetricsOptions options;
  options.radius_m = 0.25;
  options.threads = 2;
  options.max_query_points = 17;  // ignored: every point is measured
  const PointMetricFields metrics = point_metric_fields(xyz, options);
  ASSERT_EQ(metrics.fields.size(), 3u);
  ASSERT_EQ(metrics.no_data.size(), 3u);
  EXPECT_EQ(metrics.fields[0].name, "density");
  EXPECT_EQ(metrics.fields[1].name, "roughness");
  EXPECT_EQ(metrics.fields[2].name, "planarity");
  for (const auto& field : metrics.fields) ASSERT_EQ(field.values.size(), xyz.size());

  const double r2 = 0.25 * 0.25, area = M_PI * r2;
  for (size_t k = 0; k < xyz.size(); k += 37) {
    std::vector<Eigen::Vector3d> others;
    size_t within = 0;
    for (size_t j = 0; j < xyz.size(); ++j) {
      if ((xyz[j] - xyz[k]).cast<double>().squaredNorm() > r2) continue;
      ++within;
      if (j != k) others.push_back(xyz[j].cast<double>());
    }
    EXPECT_FLOAT_EQ(metrics.fields[0].values[k], static_cast<float>(within / area)) << k;
    EXPECT_NEAR(metrics.fields[1].values[k], plane_distance(others, xyz[k].cast<double>()), 1e-5)
        << k;
  }
  // The lone point: defined density, roughness and planarity at their no_data, which lies below
  // every defined value.
  const size_t lone = xyz.size() - 1;
  EXPECT_FLOAT_EQ(metrics.fields[0].values[lone], static_cast<float>(1.0 / area));
  for (size_t f = 1; f < 3; ++f) {
    EXPECT_EQ(metrics.fields[f].values[lone], metrics.no_data[f]);
    for (size_t k = 0; k < lone; ++k) EXPECT_GT(metrics.fields[f].values[k], metrics.no_data[f]);
  }
}

}  // namespace
}  // namespace keel::pipeline
