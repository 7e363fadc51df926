// Table III filters against brute-force oracles, PCL's own filters and PCL's bun0 answers.
#include <gtest/gtest.h>

#include <pcl/filters/crop_box.h>
#include <pcl/filters/radius_outlier_removal.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <set>
#include <tuple>

#include "tests/worker/mapping/test_clouds.h"
#include "worker/mapping/filter_chain.h"
#include "worker/mapping/filters.h"
#include "worker/mapping/radius_search.h"

namespace keel::mapping {
namespace {

using testing::random_cloud;

std::set<int> kept_ids(const PointCloud& cloud) {
  std::set<int> ids;
  for (float id : cloud.intensity) ids.insert(static_cast<int>(id));
  return ids;
}

pcl::PointCloud<pcl::PointXYZ>::Ptr to_pcl(const PointCloud& cloud) {
  auto out = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  for (const auto& p : cloud.xyz) out->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  return out;
}

// O(n^2) neighbour counts: (count with d < r, whether some pair sits within 1e-5 of r, where
// float rounding could tip either way).
struct BruteCount {
  int count = 0;
  bool ambiguous = false;
};
BruteCount brute_count(const PointCloud& cloud, size_t i, double radius) {
  BruteCount out;
  const Eigen::Vector3d p = cloud.xyz[i].cast<double>();
  for (size_t j = 0; j < cloud.size(); ++j) {
    const double d = (cloud.xyz[j].cast<double>() - p).norm();
    if (d < radius) ++out.count;
    if (std::abs(d - radius) < 1e-5) out.ambiguous = true;
  }
  return out;
}

TEST(CropBox, KeepsOrRemovesTheInsideLikePcl) {
  const PointCloud cloud = random_cloud(5000, -3.0f, 3.0f, 1);
  for (bool remove_inside : {false, true}) {
    CropBoxFilter filter{{-1.0, -2.0, -0.5}, {1.5, 0.5, 2.0}, remove_inside};
    PointCloud ours = cloud;
    apply_crop_box(filter, ours);
    std::set<int> expected;
    for (size_t k = 0; k < cloud.size(); ++k) {
      const Eigen::Vector3d p = cloud.xyz[k].cast<double>();
      const bool inside =
          (p.array() >= filter.min_m.array()).all() && (p.array() <= filter.max_m.array()).all();
      if (inside != remove_inside) expected.insert(static_cast<int>(k));
    }
    EXPECT_EQ(kept_ids(ours), expected);

    pcl::CropBox<pcl::PointXYZ> pcl_box;
    pcl_box.setInputCloud(to_pcl(cloud));
    pcl_box.setMin(Eigen::Vector4f(-1.0f, -2.0f, -0.5f, 1.0f));
    pcl_box.setMax(Eigen::Vector4f(1.5f, 0.5f, 2.0f, 1.0f));
    pcl_box.setNegative(remove_inside);
    pcl::PointCloud<pcl::PointXYZ> pcl_out;
    pcl_box.filter(pcl_out);
    EXPECT_EQ(pcl_out.size(), ours.size());
  }
}

// Exact centroids by voxel (ints from floor(p / leaf) in double, as ours).
std::map<std::tuple<int64_t, int64_t, int64_t>, Eigen::Vector3d> oracle_voxels(
    const PointCloud& cloud, double leaf) {
  std::map<std::tuple<int64_t, int64_t, int64_t>, std::pair<Eigen::Vector3d, int>> sums;
  for (const auto& p : cloud.xyz) {
    const auto key = std::make_tuple(static_cast<int64_t>(std::floor(p.x() / leaf)),
                                     static_cast<int64_t>(std::floor(p.y() / leaf)),
                                     static_cast<int64_t>(std::floor(p.z() / leaf)));
    auto& [sum, count] = sums[key];
    if (count == 0) sum.setZero();
    sum += p.cast<double>();
    ++count;
  }
  std::map<std::tuple<int64_t, int64_t, int64_t>, Eigen::Vector3d> out;
  for (const auto& [key, value] : sums) out[key] = value.first / value.second;
  return out;
}

void expect_voxel_grid_matches_oracle(const PointCloud& cloud, double leaf, double tolerance) {
  PointCloud ours = cloud;
  apply_voxel_grid(VoxelGridFilter{leaf}, ours);
  const auto expected = oracle_voxels(cloud, leaf);
  ASSERT_EQ(ours.size(), expected.size());
  // Each output point is the centroid of the voxel it lies in (a voxel is convex).
  for (size_t k = 0; k < ours.size(); ++k) {
    const Eigen::Vector3f& p = ours.xyz[k];
    const auto key = std::make_tuple(static_cast<int64_t>(std::floor(p.x() / leaf)),
                                     static_cast<int64_t>(std::floor(p.y() / leaf)),
                                     static_cast<int64_t>(std::floor(p.z() / leaf)));
    const auto found = expected.find(key);
    ASSERT_NE(found, expected.end()) << k;
    ASSERT_LT((p.cast<double>() - found->second).norm(), tolerance) << k;
  }
}

TEST(VoxelGrid, ExactCentroidsAndPclAgreement) {
  PointCloud cloud = random_cloud(20000, -2.0f, 2.0f, 2);
  expect_voxel_grid_matches_oracle(cloud, 0.25, 1e-6);
  // Intensity is averaged with the positions (here: the mean of the member indices).
  PointCloud ours = cloud;
  apply_voxel_grid(VoxelGridFilter{0.25}, ours);
  ASSERT_TRUE(ours.has_intensity());

  pcl::VoxelGrid<pcl::PointXYZ> pcl_grid;
  pcl_grid.setInputCloud(to_pcl(cloud));
  pcl_grid.setLeafSize(0.25f, 0.25f, 0.25f);
  pcl::PointCloud<pcl::PointXYZ> pcl_out;
  pcl_grid.filter(pcl_out);
  EXPECT_EQ(pcl_out.size(), ours.size());
}

TEST(VoxelGrid, ExtentOverLeafBeyondPclsThirtyTwoBitIndex) {
  // A 4 km survey at a 1 cm leaf: (4e5)^3 = 6.4e16 voxels, far past 2^31.
  PointCloud cloud = random_cloud(5000, 0.0f, 4000.0f, 3);
  // Plus clusters of points that share a voxel.
  for (int c = 0; c < 50; ++c) {
    const Eigen::Vector3f base = cloud.xyz[c].array().floor() + 0.001f;
    for (int m = 0; m < 4; ++m) {
      cloud.xyz.push_back(base + Eigen::Vector3f::Constant(0.002f * m));
      cloud.intensity.push_back(0.0f);
    }
  }
  expect_voxel_grid_matches_oracle(cloud, 0.01, 1e-3);

  // PCL refuses this cloud (it warns and leaves it unfiltered).
  pcl::VoxelGrid<pcl::PointXYZ> pcl_grid;
  pcl_grid.setInputCloud(to_pcl(cloud));
  pcl_grid.setLeafSize(0.01f, 0.01f, 0.01f);
  pcl::PointCloud<pcl::PointXYZ> pcl_out;
  pcl_grid.filter(pcl_out);
  PointCloud ours = cloud;
  apply_voxel_grid(VoxelGridFilter{0.01}, ours);
  EXPECT_EQ(ours.size(), cloud.size() - 50 * 3);  // each cluster of 4 becomes 1
  EXPECT_NE(pcl_out.size(), ours.size());

  // Even beyond 2^63 voxels in total (1e5 m extent at 1e-4 m), indices are per axis.
  expect_voxel_grid_matches_oracle(random_cloud(2000, -5e4f, 5e4f, 4), 1e-4, 1e-2);
}

TEST(VoxelGrid, RejectsBadLeaf) {
  PointCloud cloud = random_cloud(10, 0.0f, 1.0f, 5);
  EXPECT_THROW(apply_voxel_grid(VoxelGridFilter{0.0}, cloud), std::invalid_argument);
  EXPECT_THROW(apply_voxel_grid(VoxelGridFilter{-1.0}, cloud), std::invalid_argument);
  EXPECT_THROW(apply_voxel_grid(VoxelGridFilter{std::nan("")}, cloud), std::invalid_argument);
}

TEST(RadiusOutlierRemoval, MatchesBruteForceAndPcl) {
  const PointCloud cloud = random_cloud(3000, 0.0f, 2.0f, 6);
  const RadiusOutlierFilter filter{0.15, 4};
  PointCloud ours = cloud;
  apply_radius_outlier(filter, ours, 2);
  const std::set<int> kept = kept_ids(ours);
  size_t checked = 0;
  for (size_t k = 0; k < cloud.size(); ++k) {
    const BruteCount brute = brute_count(cloud, k, filter.radius_m);
    if (brute.ambiguous) continue;
    ++checked;
    // PCL semantics: at least min_neighbors OTHER points within r.
    ASSERT_EQ(kept.count(static_cast<int>(k)) == 1, brute.count - 1 >= filter.min_neighbors) << k;
  }
  EXPECT_GT(checked, 2900u);
  EXPECT_GT(ours.size(), 100u);
  EXPECT_LT(ours.size(), cloud.size() - 100);  // both outcomes occur

  pcl::RadiusOutlierRemoval<pcl::PointXYZ> pcl_ror;
  pcl_ror.setInputCloud(to_pcl(cloud));
  pcl_ror.setRadiusSearch(filter.radius_m);
  pcl_ror.setMinNeighborsInRadius(filter.min_neighbors);
  pcl::PointCloud<pcl::PointXYZ> pcl_out;
  pcl_ror.filter(pcl_out);
  EXPECT_NEAR(static_cast<double>(pcl_out.size()), static_cast<double>(ours.size()),
              cloud.size() - checked);
}

TEST(Dror, MatchesBruteForceWithRangeDependentRadius) {
  // A scan-like cloud in the sensor frame: ranges 1..40 m, so SR spans SR_min..~0.6 m.
  PointCloud cloud;
  std::mt19937 rng(8);
  std::uniform_real_distribution<float> angle(-3.14159f, 3.14159f), range(1.0f, 40.0f),
      height(-2.0f, 2.0f);
  for (int k = 0; k < 4000; ++k) {
    const float a = angle(rng), r = range(rng);
    cloud.xyz.emplace_back(r * std::cos(a), r * std::sin(a), height(rng));
    cloud.intensity.push_back(static_cast<float>(k));
  }
  const DrorFilter filter{3.0, 1.0, 4, 0.05};
  PointCloud ours = cloud;
  apply_dror(filter, ours, 2);
  const std::set<int> kept = kept_ids(ours);
  size_t checked = 0;
  for (size_t k = 0; k < cloud.size(); ++k) {
    const Eigen::Vector3f& p = cloud.xyz[k];
    const double r_xy = std::hypot(static_cast<double>(p.x()), static_cast<double>(p.y()));
    const double radius = std::max(3.0 * (1.0 * M_PI / 180.0) * r_xy, 0.05);
    EXPECT_DOUBLE_EQ(dror_search_radius(filter, r_xy), radius);
    const BruteCount brute = brute_count(cloud, k, radius);
    if (brute.ambiguous) continue;
    ++checked;
    ASSERT_EQ(kept.count(static_cast<int>(k)) == 1, brute.count >= filter.k_min) << k;
  }
  EXPECT_GT(checked, 3900u);
  EXPECT_GT(ours.size(), 100u);
  EXPECT_LT(ours.size(), cloud.size() - 100);
}

// A spinning-lidar-like scan in its sensor frame: 16 rings x `azimuths` returns `step_deg`
// apart (0.2: a VLP-16 at 10 Hz, Table IV's alpha) off walls at 4..12 m
// with range noise, a few dropouts and isolated spurious returns (rain, spray), so
// DROR keeps most points and removes some, and a point's neighbours sit on its own ring,
// often across a kd-tree leaf boundary.
PointCloud ring_scan(int azimuths, float step_deg, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::normal_distribution<float> noise(0.0f, 0.01f);
  PointCloud cloud;
  const float kDeg = 3.14159265f / 180.0f;
  for (int ring = 0; ring < 16; ++ring) {
    const float elevation = (-15.0f + 2.0f * ring) * kDeg;
    for (int a = 0; a < azimuths; ++a) {
      if (u(rng) < 0.05f) continue;  // dropout
      const float azimuth = a * step_deg * kDeg;
      const float wall = 8.0f + 4.0f * std::sin(2.0f * azimuth);
      const float range = u(rng) < 0.05f ? 1.0f + 29.0f * u(rng) : wall + noise(rng);
      cloud.xyz.emplace_back(range * std::cos(elevation) * std::cos(azimuth),
                             range * std::cos(elevation) * std::sin(azimuth),
                             range * std::sin(elevation));
      cloud.intensity.push_back(static_cast<float>(cloud.xyz.size() - 1));
    }
  }
  return cloud;
}

// Brute-force counts with the search's own float arithmetic, ((dx^2 + dy^2) + dz^2) < r^2:
// the capped counts must then agree exactly, boundary cases included.
int float_brute_count(const std::vector<Eigen::Vector3f>& points, const Eigen::Vector3f& q,
                      double radius) {
  const float r2 = static_cast<float>(radius * radius);
  int count = 0;
  for (const Eigen::Vector3f& p : points) {
    const float dx = q.x() - p.x(), dy = q.y() - p.y(), dz = q.z() - p.z();
    count += dx * dx + dy * dy + dz * dz < r2;
  }
  return count;
}

void expect_counts_match_brute_force(const std::vector<Eigen::Vector3f>& points, size_t stride) {
  const RadiusSearch search(points);
  ASSERT_EQ(search.size(), points.size());
  std::vector<uint32_t> order = search.spatial_order();
  std::sort(order.begin(), order.end());
  for (size_t i = 0; i < order.size(); ++i) ASSERT_EQ(order[i], i);  // a permutation
  size_t early = 0;
  for (size_t rank = 0; rank < points.size(); rank += stride) {
    const Eigen::Vector3f& q = points[search.spatial_order()[rank]];
    for (double radius : {0.01, 0.05, 0.2, 0.6}) {
      const int brute = float_brute_count(points, q, radius);
      ASSERT_EQ(search.count_within(q, radius), brute) << rank << " r " << radius;
      for (int cap : {1, 2, 4, 9, 40}) {
        const int around = search.count_around(rank, radius, cap);
        ASSERT_EQ(around, std::min(brute, cap)) << rank << " r " << radius << " cap " << cap;
        ASSERT_EQ(search.count_within(q, radius, cap), std::min(brute, cap));
        early += brute > cap;
      }
    }
  }
  EXPECT_GT(early, points.size() / stride);  // capped counts (early exits) did occur
}

TEST(RadiusSearch, CappedCountsMatchBruteForceOnAScan) {
  expect_counts_match_brute_force(ring_scan(450, 0.8f, 11).xyz, 1);
}

TEST(RadiusSearch, CappedCountsMatchBruteForceOnClustersAndALargeCloud) {
  // Tight clusters (many points per leaf within a small radius) plus uniform clutter.
  std::mt19937 rng(12);
  std::normal_distribution<float> spread(0.0f, 0.03f);
  std::vector<Eigen::Vector3f> clusters = random_cloud(300, 0.0f, 3.0f, 13).xyz;
  for (size_t c = 0, n = clusters.size(); c < n; c += 3) {
    for (int k = 0; k < 8; ++k) {
      clusters.push_back(clusters[c] + Eigen::Vector3f(spread(rng), spread(rng), spread(rng)));
    }
  }
  expect_counts_match_brute_force(clusters, 1);
  // Above the Morton threshold (2^16 points): the stored order differs, answers must not.
  expect_counts_match_brute_force(random_cloud(70000, 0.0f, 4.0f, 14).xyz, 997);
}

TEST(Dror, MatchesBruteForceOnARingScan) {
  const PointCloud cloud = ring_scan(450, 0.2f, 15);
  const DrorFilter filter;  // Table IV lidar defaults
  for (int threads : {1, 2}) {
    PointCloud ours = cloud;
    apply_dror(filter, ours, threads);
    const std::set<int> kept = kept_ids(ours);
    size_t checked = 0;
    for (size_t k = 0; k < cloud.size(); ++k) {
      const Eigen::Vector3f& p = cloud.xyz[k];
      const double radius = dror_search_radius(filter, std::hypot(p.x(), p.y()));
      const BruteCount brute = brute_count(cloud, k, radius);
      if (brute.ambiguous) continue;
      ++checked;
      ASSERT_EQ(kept.count(static_cast<int>(k)) == 1, brute.count >= filter.k_min) << k;
    }
    EXPECT_GT(checked, cloud.size() * 95 / 100);
    EXPECT_GT(ours.size(), cloud.size() / 2);
    EXPECT_LT(ours.size(), cloud.size() - 100);  // the spurious returns go
  }
}

TEST(Bun0, PclPublishedAnswers) {
  const std::filesystem::path path = std::filesystem::path(KEEL_SHARED_DIR) / "data" / "bun0.pcd";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " absent (…/shared absent)";
  pcl::PointCloud<pcl::PointXYZ> bunny;
  ASSERT_EQ(pcl::io::loadPCDFile(path.string(), bunny), 0);
  ASSERT_EQ(bunny.size(), 397u);
  PointCloud cloud;
  for (const auto& p : bunny) cloud.xyz.emplace_back(p.x, p.y, p.z);

  PointCloud voxelized = cloud;
  apply_voxel_grid(VoxelGridFilter{0.02}, voxelized);
  EXPECT_EQ(voxelized.size(), 103u);

  PointCloud ror = cloud;
  const size_t removed = apply_radius_outlier(RadiusOutlierFilter{0.02, 14}, ror, 2);
  EXPECT_EQ(ror.size(), 307u);
  EXPECT_EQ(removed, 90u);
}

TEST(FilterChain, JsonRoundTripAndTableIvDefaults) {
  const nlohmann::json json = nlohmann::json::parse(R"([
    {"type": "crop_box", "min": [-60, -60, -60], "max": [60, 60, 60], "remove": "outside"},
    {"type": "crop_box", "min": [-2, -2, -2], "max": [2, 2, 2], "remove": "inside"},
    {"type": "dror", "beta": 3.0, "alpha_deg": 0.2, "k_min": 4, "sr_min": 0.01}])");
  const FilterChain chain = filter_chain_from_json(json, "map.filters");
  EXPECT_EQ(filter_chain_to_json(chain), filter_chain_to_json(table_iv_lidar_scan_filters()));
  EXPECT_EQ(filter_chain_from_json(filter_chain_to_json(chain), "x").filters.size(), 3u);

  // The chain applies in order and reports each step.
  PointCloud cloud = random_cloud(2000, -70.0f, 70.0f, 9);
  cloud.xyz.emplace_back(0.5f, 0.5f, 0.5f);  // on the vessel
  cloud.intensity.push_back(-1.0f);
  const std::vector<FilterStep> steps = apply_filter_chain(chain, cloud);
  ASSERT_EQ(steps.size(), 3u);
  EXPECT_EQ(steps[0].filter, "crop_box");
  EXPECT_EQ(steps[0].points_in, 2001u);
  EXPECT_EQ(steps[1].points_in, steps[0].points_out);
  EXPECT_EQ(steps[1].points_out, steps[0].points_out - 1);
  EXPECT_EQ(steps[2].filter, "dror");
  EXPECT_EQ(cloud.size(), steps[2].points_out);
}

void expect_error(const std::string& text, const std::string& needle) {
  try {
    filter_chain_from_json(nlohmann::json::parse(text), "map.filters");
    FAIL() << "accepted " << text;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST(FilterChain, ErrorsNameTheField) {
  expect_error(R"([{"type": "voxel_grid", "leaf": 0.1}, {"type": "voxel_grid", "leaf": -1}])",
               "map.filters[1].leaf");
  expect_error(R"([{"type": "median"}])", "map.filters[0].type");
  expect_error(R"([{"type": "ror", "radius": 0.1, "min_neigbors": 3}])",
               "map.filters[0].min_neigbors: unknown key");
  expect_error(R"([{"type": "crop_box", "max": [1, 1, 1]}])", "map.filters[0].min");
  expect_error(R"([{"type": "crop_box", "min": [0, 0], "max": [1, 1, 1]}])", "map.filters[0].min");
  expect_error(R"([{"type": "crop_box", "min": [0, 0, 0], "max": [1, 1, 1], "remove": "up"}])",
               "map.filters[0].remove");
  expect_error(R"({"type": "voxel_grid"})", "expected an array");
  expect_error(R"([{"type": "dror", "k_min": 2.5}])", "map.filters[0].k_min");
}

}  // namespace
}  // namespace keel::mapping
