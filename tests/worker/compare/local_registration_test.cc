// The per-tile registration (compare/local_registration.h) against known offsets: a change
// over half a tile does not move it, a whole-tile offset is removed, and only the directions
// the structure constrains are corrected.
#include "worker/compare/local_registration.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <random>
#include <vector>

namespace keel::compare {
namespace {

struct Face {
  Eigen::Vector3d origin, u, v;  // the rectangle origin + [0, 1] u + [0, 1] v
};

// The faces of the box [1, 7] x [1, 7] x [1, 5] inside the tile [0, 10)^3.
std::vector<Face> box_faces() {
  const Eigen::Vector3d lo(1, 1, 1), e(6, 6, 4);
  const Eigen::Vector3d X = Eigen::Vector3d::UnitX() * e.x(), Y = Eigen::Vector3d::UnitY() * e.y(),
                        Z = Eigen::Vector3d::UnitZ() * e.z();
  return {{lo, X, Y}, {lo + Z, X, Y}, {lo, X, Z}, {lo + Y, X, Z}, {lo, Y, Z}, {lo + X, Y, Z}};
}

// Noisy samples of the faces (density per m^2, Gaussian noise along each face's normal);
// `offset(p, n)` displaces a sample at p on a face of unit normal n.
template <typename Offset>
std::vector<Eigen::Vector3f> sample(const std::vector<Face>& faces, double density, double sigma_m,
                                    uint32_t seed, Offset offset) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, sigma_m);
  std::vector<Eigen::Vector3f> out;
  for (const Face& f : faces) {
    const Eigen::Vector3d n = f.u.cross(f.v).normalized();
    const size_t count = size_t(f.u.cross(f.v).norm() * density);
    for (size_t i = 0; i < count; ++i) {
      const Eigen::Vector3d p = f.origin + unit(rng) * f.u + unit(rng) * f.v;
      const Eigen::Vector3d q = p + noise(rng) * n + Eigen::Vector3d(offset(p, n));
      out.push_back(q.cast<float>());
    }
  }
  return out;
}

Eigen::Vector3d none(const Eigen::Vector3d&, const Eigen::Vector3d&) {
  return Eigen::Vector3d::Zero();
}

double largest_motion(const std::vector<Eigen::Vector3f>& before,
                      const std::vector<Eigen::Vector3f>& after) {
  double out = 0.0;
  for (size_t i = 0; i < before.size(); ++i)
    out = std::max(out, double((after[i] - before[i]).norm()));
  return out;
}

TEST(LocalRegistration, ChangeOverHalfTheTileDoesNotMoveIt) {
  const std::vector<Face> faces = box_faces();
  const auto a = sample(faces, 1500, 0.004, 1, none);
  // Every surface with x < 4 (half the box) lies 3 cm further out in B.
  const auto b =
      sample(faces, 1500, 0.004, 2, [](const Eigen::Vector3d& p, const Eigen::Vector3d& n) {
        return p.x() < 4.0 ? Eigen::Vector3d(0.03 * n) : Eigen::Vector3d::Zero();
      });
  std::vector<Eigen::Vector3f> moved = b;
  const LocalRegistration r = register_tiles(a, &moved, {});
  ASSERT_EQ(r.tiles.size(), 1u);
  EXPECT_LT(largest_motion(b, moved), 0.002) << r.tiles[0].correction.status;
}

TEST(LocalRegistration, WholeTileOffsetIsRemoved) {
  const std::vector<Face> faces = box_faces();
  const auto a = sample(faces, 1500, 0.004, 1, none);
  const auto truth = sample(faces, 1500, 0.004, 2, none);
  Pose3 T = Pose3::Identity();
  const Eigen::Vector3d center(4, 4, 3);
  T.linear() = Eigen::AngleAxisd(0.15 * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = center + Eigen::Vector3d(0.02, -0.015, 0.025) - T.linear() * center;
  std::vector<Eigen::Vector3f> moved;
  for (const auto& p : truth) moved.push_back((T * p.cast<double>()).cast<float>());
  const LocalRegistration r = register_tiles(a, &moved, {});
  ASSERT_EQ(r.tiles.size(), 1u);
  EXPECT_EQ(r.tiles[0].correction.status, "corrected");
  EXPECT_EQ(r.tiles[0].correction.fixed_directions.size(), 6u);
  EXPECT_LT(largest_motion(truth, moved), 0.003);
}

TEST(LocalRegistration, OnlyTheDirectionsAWallConstrainsAreCorrected) {
  // One wall x = 2: its normal's translation (and the tilts out of it) are fixed, the slide
  // along it is not; B is 2 cm off the wall and 5 cm along it.
  const std::vector<Face> wall = {{{2, 1, 1}, {0, 8, 0}, {0, 0, 8}}};
  const auto a = sample(wall, 1500, 0.004, 1, none);
  const auto truth = sample(wall, 1500, 0.004, 2, none);
  const Eigen::Vector3f offset(0.02f, 0.05f, 0.0f);
  std::vector<Eigen::Vector3f> moved;
  for (const auto& p : truth) moved.push_back(p + offset);
  const LocalRegistration r = register_tiles(a, &moved, {});
  ASSERT_EQ(r.tiles.size(), 1u);
  const TileCorrection& c = r.tiles[0].correction;
  EXPECT_EQ(c.status, "corrected");
  EXPECT_EQ(c.fixed_directions, (std::vector<std::string>{"ry", "rz", "tx"}));
  for (size_t i = 0; i < truth.size(); i += 97) {
    EXPECT_NEAR(moved[i].x(), truth[i].x(), 0.003);
    EXPECT_NEAR(moved[i].y() - truth[i].y(), 0.05, 0.003);  // along the wall: not corrected
  }
}

}  // namespace
}  // namespace keel::compare
