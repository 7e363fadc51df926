// Shapes of two hull surveys matched into kept, new and gone, the frame offset the persisting
// ones agree on, and each kept shape's growth with its sigma: hand-made cases.
#include "worker/compare/shape_matching.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <utility>

namespace keel::compare {
namespace {

SurveyShape shape_at(double x, double y, double z, double radius_m = 0.1) {
  SurveyShape s;
  s.centroid_model = Eigen::Vector3d(x, y, z);
  s.radius_m = radius_m;
  return s;
}

TEST(MatchShapes, OverlappingFootprintsPairNearestFirstEachShapeOnce) {
  // B's 0 overlaps A's 0 (0.05 m) and A's 1 (0.15 m); B's 1 overlaps A's 1 only (0.18 m).
  // Nearest first: (0, 0), then A's 1 takes B's 1; B's 2 is too far from every shape of A.
  const std::vector<SurveyShape> a = {shape_at(0, 0, 0), shape_at(0.2, 0, 0), shape_at(5, 0, 0)};
  const std::vector<SurveyShape> b = {shape_at(0.05, 0, 0), shape_at(0.38, 0, 0),
                                      shape_at(0, 3, 0)};
  const std::vector<ShapeMatch> m = match_shapes(a, b);
  ASSERT_EQ(m.size(), 4u);
  EXPECT_EQ(std::make_pair(m[0].a, m[0].b), std::make_pair(0, 0));
  EXPECT_NEAR(m[0].distance_m, 0.05, 1e-12);
  EXPECT_EQ(std::make_pair(m[1].a, m[1].b), std::make_pair(1, 1));
  EXPECT_NEAR(m[1].distance_m, 0.18, 1e-12);
  EXPECT_EQ(std::make_pair(m[2].a, m[2].b), std::make_pair(2, -1));  // gone
  EXPECT_EQ(std::make_pair(m[3].a, m[3].b), std::make_pair(-1, 2));  // new
  // Discs that only touch (distance = r_a + r_b) do not overlap.
  EXPECT_EQ(match_shapes({shape_at(0, 0, 0)}, {shape_at(0.2, 0, 0)}).size(), 2u);
}

TEST(RegisterShapes, PersistingShapesAgreeOnTheSurveysFrameOffset) {
  // Three objects persist, seen 0.3 m further along the hull in B (x_gM loose along it) with
  // centroid noise of a centimetre; A's fourth is gone, B's fourth is new.
  const Eigen::Vector3d t(0.3, 0.0, 0.0);
  const std::vector<SurveyShape> a = {shape_at(-3, -5, -1.2), shape_at(3, -4, -3.8),
                                      shape_at(-1, -3, -3.9), shape_at(1.8, -5, -2.1)};
  std::vector<SurveyShape> b = {shape_at(-3 + 0.31, -5.01, -1.2), shape_at(3 + 0.29, -4, -3.79),
                                shape_at(-1 + 0.30, -2.99, -3.9), shape_at(0.5, -2.9, -3.9)};
  // Where each survey's x_gM put them, no footprints overlap: three gone, four new.
  int kept = 0;
  for (const ShapeMatch& m : match_shapes(a, b)) kept += m.a >= 0 && m.b >= 0;
  EXPECT_EQ(kept, 0);

  const ShapeRegistration r = register_shapes(a, b, 1.0);
  EXPECT_EQ(r.pairs, 3);
  EXPECT_NEAR((r.translation_model - t).norm(), 0.0, 1e-9 + 0.01 / std::sqrt(3.0));
  std::vector<SurveyShape> moved = a;
  for (auto& s : moved) s.centroid_model += r.translation_model;
  std::set<std::pair<int, int>> pairs;
  for (const ShapeMatch& m : match_shapes(moved, b)) pairs.insert({m.a, m.b});
  EXPECT_EQ(pairs, (std::set<std::pair<int, int>>{{0, 0}, {1, 1}, {2, 2}, {3, -1}, {-1, 3}}));

  // Beyond max_offset_m, or a single persisting object: no offset is applied.
  EXPECT_EQ(register_shapes(a, b, 0.2).pairs, 0);
  EXPECT_EQ(register_shapes(a, b, 0.2).translation_model, Eigen::Vector3d::Zero());
  const ShapeRegistration one = register_shapes({a[0]}, {b[0]}, 1.0);
  EXPECT_EQ(one.pairs, 0);
  EXPECT_EQ(one.translation_model, Eigen::Vector3d::Zero());
}

TEST(ShapeGrowth, HeightAndFootprintGrowthWithTheirSigmas) {
  SurveyShape a = shape_at(0, 0, 0, 0.1), b = shape_at(0, 0, 0, 0.2);
  a.height_m = 0.10;
  b.height_m = 0.15;
  a.height_sampling_sigma_m = 0.004;
  b.height_sampling_sigma_m = 0.012;
  const SurveySigmas sigma_a{0.003, 0.05}, sigma_b{0.003, 0.05};
  const ShapeGrowth g = shape_growth(a, b, sigma_a, sigma_b, 1.96);
  EXPECT_NEAR(g.height_m, 0.05, 1e-12);
  // sqrt(3^2 + 3^2 + 4^2 + 12^2) mm.
  EXPECT_NEAR(g.height_sigma_m, std::sqrt(178.0) * 1e-3, 1e-15);
  EXPECT_NEAR(g.footprint_a_m2, M_PI * 0.01, 1e-15);
  EXPECT_NEAR(g.footprint_b_m2, M_PI * 0.04, 1e-15);
  // 2 pi r dr of each survey in quadrature: 2 pi 0.05 sqrt(0.1^2 + 0.2^2).
  EXPECT_NEAR(g.footprint_sigma_m2, 2 * M_PI * 0.05 * std::sqrt(0.05), 1e-15);
  EXPECT_TRUE(g.significant);                                           // 0.05 > 1.96 x 0.0133
  EXPECT_FALSE(shape_growth(a, b, sigma_a, sigma_b, 4.0).significant);  // 4 x 0.0133 > 0.05
  EXPECT_TRUE(shape_growth(b, a, sigma_b, sigma_a, 1.96).significant);  // shrinking counts too
}

TEST(CompareShapes, KeptNewGoneAndGrownAfterTheFrameOffset) {
  // Two objects persist 0.3 m along x in B, the first 5 cm higher; A's third is gone, B's
  // third new. Without the offset every footprint would miss.
  std::vector<SurveyShape> a = {shape_at(0, 0, 0), shape_at(2, 0, 0), shape_at(4, 0, 0)};
  std::vector<SurveyShape> b = {shape_at(0.3, 0, 0), shape_at(2.3, 0, 0), shape_at(0, 4, 0)};
  for (auto& s : a) s.height_m = 0.1;
  for (auto& s : b) s.height_m = 0.1;
  b[0].height_m = 0.15;
  const ShapeChanges c = compare_shapes(a, b, {0.01, 0.0}, {0.01, 0.0}, 1.0, 1.96);
  EXPECT_EQ(c.registration.pairs, 2);
  EXPECT_NEAR((c.registration.translation_model - Eigen::Vector3d(0.3, 0, 0)).norm(), 0.0, 1e-12);
  EXPECT_NEAR(c.a_moved[2].centroid_model.x(), 4.3, 1e-12);
  EXPECT_EQ(c.kept, 2);
  EXPECT_EQ(c.added, 1);
  EXPECT_EQ(c.gone, 1);
  EXPECT_EQ(c.grown, 1);
  ASSERT_EQ(c.changes.size(), 4u);
  for (const ShapeChange& change : c.changes) {
    if (change.match.a != 0) continue;
    EXPECT_EQ(change.match.b, 0);
    EXPECT_NEAR(change.growth.height_m, 0.05, 1e-12);
    EXPECT_NEAR(change.growth.height_sigma_m, 0.01 * std::sqrt(2.0), 1e-15);
    EXPECT_TRUE(change.growth.significant);
  }
  // With the offset not corrected, nothing is kept.
  const ShapeChanges raw = compare_shapes(a, b, {0.01, 0.0}, {0.01, 0.0}, 0.0, 1.96);
  EXPECT_EQ(raw.kept, 0);
  EXPECT_EQ(raw.added, 3);
  EXPECT_EQ(raw.gone, 3);
}

}  // namespace
}  // namespace keel::compare
