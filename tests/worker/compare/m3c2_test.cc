// M3C2 on analytic surfaces: two parallel noisy planes 2 cm apart, a sphere grown by 1 cm,
// a surface compared with itself; the 95 % confidence must hold ~95 % of the time.
#include "worker/compare/m3c2.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "tests/worker/compare/test_surfaces.h"

namespace keel::compare {
namespace {

using testing::sample_rectangle;
using testing::sample_sphere;

struct M3c2Run {
  std::vector<CoreChange> cores;
  size_t defined = 0, covered = 0, significant = 0;
  double mean = 0.0;
};

// Core points: B's voxel centroids, as the stage takes them.
M3c2Run run_m3c2(const std::vector<Eigen::Vector3f>& a, const std::vector<Eigen::Vector3f>& b,
                 const std::vector<Eigen::Vector3f>& viewpoints, const M3c2Options& options,
                 double true_change_m) {
  const NearestIndex ia(a), ib(b);
  const VoxelMoments va = voxelize(a, options.normal_scale_m / 4),
                     vb = voxelize(b, options.normal_scale_m / 4);
  const VoxelMoments cores = voxelize(b, options.core_spacing_m);
  std::vector<Eigen::Vector3f> positions;
  for (const auto& m : cores.voxels) positions.push_back(m.mean.cast<float>());
  M3c2Run run;
  run.cores = m3c2({&ia, &ib, &va, &vb}, positions, viewpoints, options);
  for (const CoreChange& c : run.cores) {
    if (!c.defined()) continue;
    ++run.defined;
    run.mean += c.distance_m;
    run.covered += std::abs(c.distance_m - true_change_m) <= c.lod95_m;
    run.significant += c.significant;
  }
  run.mean /= std::max<size_t>(run.defined, 1);
  return run;
}

TEST(M3c2, ParallelPlanesTwoCentimetresApart) {
  std::mt19937 rng(3);
  std::vector<Eigen::Vector3f> a, b;
  const Eigen::Vector3d X = Eigen::Vector3d::UnitX(), Y = Eigen::Vector3d::UnitY();
  const double sigma = 0.005;
  sample_rectangle({0, 0, 0}, X, 4, Y, 4, 2500, sigma, rng, &a);
  sample_rectangle({0, 0, 0.02}, X, 4, Y, 4, 2500, sigma, rng, &b);
  M3c2Options options;
  const M3c2Run run = run_m3c2(a, b, {}, options, 0.02);
  ASSERT_GT(run.defined, 1000u);
  // Inner cores have ~79 points per cylinder and cloud: the mean of d is 2 cm within a few
  // tenths of a millimetre, and each core's 95 % interval holds the true 2 cm ~95 % of the time.
  EXPECT_NEAR(run.mean, 0.02, 3e-4);
  const double coverage = double(run.covered) / run.defined;
  EXPECT_GT(coverage, 0.92);
  EXPECT_LT(coverage, 0.98);
  // LoD95 = 1.96 sqrt(2 sigma^2 / n) ~ 1.6 mm << 2 cm: every defined core is significant.
  EXPECT_EQ(run.significant, run.defined);
  for (const CoreChange& c : run.cores) {
    if (!c.defined()) continue;
    EXPECT_NEAR(std::abs(c.normal.z()), 1.0, 1e-3);
    EXPECT_GT(c.normal.z(), 0.0f);  // +z without viewpoints
    EXPECT_NEAR(c.sigma_a_m, sigma, 0.004);
    EXPECT_NEAR(c.area_m2, 0.01, 1e-3);  // s^2 / |n|_1 with n = z
  }
}

TEST(M3c2, RegistrationErrorWidensTheInterval) {
  std::mt19937 rng(4);
  std::vector<Eigen::Vector3f> a, b;
  const Eigen::Vector3d X = Eigen::Vector3d::UnitX(), Y = Eigen::Vector3d::UnitY();
  sample_rectangle({0, 0, 0}, X, 2, Y, 2, 2500, 0.005, rng, &a);
  sample_rectangle({0, 0, 0.02}, X, 2, Y, 2, 2500, 0.005, rng, &b);
  M3c2Options options;
  options.registration_error_m = 0.02;  // LoD95 >= 1.96 * 2 cm = 3.9 cm > 2 cm
  const M3c2Run run = run_m3c2(a, b, {}, options, 0.02);
  ASSERT_GT(run.defined, 100u);
  EXPECT_EQ(run.significant, 0u);
  for (const CoreChange& c : run.cores)
    if (c.defined()) EXPECT_GE(c.lod95_m, 1.96f * 0.02f);
}

TEST(M3c2, SphereGrownByOneCentimetre) {
  std::mt19937 rng(5);
  std::vector<Eigen::Vector3f> a, b;
  sample_sphere({1, 2, 3}, 1.0, 4000, 0.002, rng, &a);
  sample_sphere({1, 2, 3}, 1.01, 4000, 0.002, rng, &b);
  // Viewpoints on a 5 m shell around the sphere (a Fibonacci lattice): normals face outwards.
  std::vector<Eigen::Vector3f> views;
  for (int k = 0; k < 400; ++k) {
    const double z = 1.0 - (2.0 * k + 1.0) / 400.0, r = std::sqrt(1.0 - z * z);
    const double phi = k * M_PI * (3.0 - std::sqrt(5.0));
    views.push_back(
        (Eigen::Vector3d(1, 2, 3) + 5.0 * Eigen::Vector3d(r * std::cos(phi), r * std::sin(phi), z))
            .cast<float>());
  }
  M3c2Options options;
  const M3c2Run run = run_m3c2(a, b, views, options, 0.01);
  ASSERT_GT(run.defined, 1000u);
  EXPECT_NEAR(run.mean, 0.01, 3e-4);
  const double coverage = double(run.covered) / run.defined;
  EXPECT_GT(coverage, 0.90);
  EXPECT_EQ(run.significant, run.defined);
  for (const CoreChange& c : run.cores) {
    if (!c.defined()) continue;
    const Eigen::Vector3f radial = (c.position - Eigen::Vector3f(1, 2, 3)).normalized();
    EXPECT_GT(c.normal.dot(radial), 0.99f);
  }
}

TEST(M3c2, SameCloudGivesZeroChange) {
  std::mt19937 rng(6);
  std::vector<Eigen::Vector3f> a;
  sample_rectangle({0, 0, 0}, Eigen::Vector3d::UnitX(), 2, Eigen::Vector3d::UnitZ(), 2, 2500, 0.01,
                   rng, &a);
  const M3c2Run run = run_m3c2(a, a, {{1, -5, 1}}, M3c2Options{}, 0.0);
  ASSERT_GT(run.defined, 100u);
  for (const CoreChange& c : run.cores) {
    if (!c.defined()) continue;
    EXPECT_NEAR(c.distance_m, 0.0f, 1e-6f);
    EXPECT_FALSE(c.significant);
    EXPECT_LT(c.normal.y(), -0.99f);  // towards the viewpoint at y = -5
  }
}

// A pier (a 2.4 m thick box) surveyed from both sides, the nearer pass on the far side: a core
// point on the +x face must take its normal from the viewpoint that sees
// that face, not the nearer one beyond the pier, so a 5 cm spall on it measures -5 cm (material
// removed) and the -x face's normals face the -x viewpoint.
TEST(M3c2, NormalsFaceTheViewpointThatSeesTheFaceNotOneBeyondThePier) {
  std::mt19937 rng(12);
  const Eigen::Vector3d Y = Eigen::Vector3d::UnitY(), Z = Eigen::Vector3d::UnitZ();
  const double density = 2500, sigma = 0.003;
  std::vector<Eigen::Vector3f> a, b;
  testing::sample_box({-1.2, -2, 0}, {1.2, 2, 4}, density, sigma, rng, &a);
  // B: the same pier, its +x face recessed 5 cm over y in [-0.4, 0.4], z in [1.6, 2.4].
  testing::sample_box({-1.2, -2, 0}, {1.2, 2, 4}, density, sigma, rng, &b);
  b.erase(std::remove_if(b.begin(), b.end(),
                         [](const Eigen::Vector3f& p) {
                           return p.x() > 1.1f && std::abs(p.y()) < 0.4f &&
                                  std::abs(p.z() - 2.0f) < 0.4f;
                         }),
          b.end());
  sample_rectangle({1.15, -0.4, 1.6}, Y, 0.8, Z, 0.8, density, sigma, rng, &b);
  // The vessel's passes: 4.8 m off the -x face, 7.8 m off the +x face.
  const std::vector<Eigen::Vector3f> views = {{-6, 0, 0}, {9, 0, 0}};
  const M3c2Run run = run_m3c2(a, b, views, M3c2Options{}, 0.0);
  size_t spall = 0, far_face = 0;
  for (const CoreChange& c : run.cores) {
    if (!c.defined()) continue;
    const Eigen::Vector3f& p = c.position;
    if (p.x() > 1.1f && std::abs(p.y()) < 0.3f && std::abs(p.z() - 2.0f) < 0.3f) {
      ++spall;
      EXPECT_GT(c.normal.x(), 0.99f) << "towards (9, 0, 0), not through the pier";
      EXPECT_NEAR(c.distance_m, -0.05f, 0.01f);
    }
    if (p.x() < -1.1f && std::abs(p.y()) < 1.5f && p.z() > 0.5f && p.z() < 3.5f) {
      ++far_face;
      EXPECT_LT(c.normal.x(), -0.99f);
    }
  }
  EXPECT_GT(spall, 20u);
  EXPECT_GT(far_face, 100u);
}

TEST(M3c2, NewStructureMeasuredAlongTheReferenceNormal) {
  // B has a 30 cm block standing on A's plane: cores on its top measure +0.3 m along A's
  // normal (the full-depth search), cores on the bare plane 0.
  std::mt19937 rng(8);
  std::vector<Eigen::Vector3f> a, b;
  const Eigen::Vector3d X = Eigen::Vector3d::UnitX(), Y = Eigen::Vector3d::UnitY();
  sample_rectangle({0, 0, 0}, X, 3, Y, 3, 2500, 0.003, rng, &a);
  sample_rectangle({0, 0, 0}, X, 3, Y, 1, 2500, 0.003, rng, &b);
  sample_rectangle({0, 2, 0}, X, 3, Y, 1, 2500, 0.003, rng, &b);
  sample_rectangle({0, 1, 0.3}, X, 3, Y, 1, 2500, 0.003, rng, &b);  // the block's top
  const M3c2Run run = run_m3c2(a, b, {}, M3c2Options{}, 0.0);
  size_t top = 0;
  for (const CoreChange& c : run.cores) {
    if (!c.defined()) continue;
    if (c.position.z() > 0.2f && c.position.y() > 1.3f && c.position.y() < 1.7f) {
      EXPECT_NEAR(c.distance_m, 0.3f, 0.003f);
      EXPECT_TRUE(c.significant);
      ++top;
    }
  }
  EXPECT_GT(top, 50u);
}

TEST(M3c2, TooFewPointsLeaveTheChangeUndefined) {
  std::vector<Eigen::Vector3f> a = {{0, 0, 0}, {0.01f, 0, 0}, {0, 0.01f, 0}, {0.01f, 0.01f, 0}};
  std::vector<Eigen::Vector3f> b = a;
  const M3c2Run run = run_m3c2(a, b, {}, M3c2Options{}, 0.0);
  ASSERT_FALSE(run.cores.empty());
  EXPECT_FALSE(run.cores[0].defined());  // 4 < min_points = 5
}

TEST(M3c2, OptionsOutOfRangeNameTheField) {
  M3c2Options o;
  o.projection_scale_m = -1;
  try {
    validate(o);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("projection_scale_m"), std::string::npos);
  }
}

}  // namespace
}  // namespace keel::compare
