// The shapes of two hull surveys (inspect's shapes.json), both in the CAD model's frame, matched
// into kept, new and gone, with the height and footprint growth of each kept shape and its
// uncertainty. A shape's footprint is a disc of radius r; two shapes are the same object when
// their discs overlap. Pure geometry: the stage reads the files (worker/stages/compare).
#pragma once

#include <Eigen/Core>

#include <vector>

namespace keel::compare {

// A shape of one survey in the model frame.
struct SurveyShape {
  int id = 0;
  Eigen::Vector3d centroid_model = Eigen::Vector3d::Zero();
  double height_m = 0.0;
  double height_sampling_sigma_m = 0.0;  // shapes.json's: how far the top may lie beyond it
  double radius_m = 0.0;                 // footprint: a disc of this radius
};

struct ShapeMatch {
  int a = -1, b = -1;  // indices into the two lists; -1 = none (new / gone)
  double distance_m = 0.0;
};

// Pairs shapes whose footprint discs overlap (centroid distance < r_a + r_b), nearest first,
// each shape at most once; the rest are gone (A only) or new (B only).
std::vector<ShapeMatch> match_shapes(const std::vector<SurveyShape>& a,
                                     const std::vector<SurveyShape>& b);

// The translation (model frame) that brings A's shapes onto B's. Each survey's x_gM is
// poorly constrained along a hull whose middle body is prismatic (keel-sim's BA: 0.2-0.5 m
// off along the hull, its own sigma ~0.09 m), so the same object may sit 0.3 m apart in
// the two model frames, beyond its footprint. Objects that persist move together: each
// pair's offset b - a is a candidate, and the candidate that the most other pairs agree
// with (within their footprint radii, one-to-one) wins; the result is the mean offset of
// those agreeing pairs. Fewer than `min_pairs` agreeing pairs (one persisting object cannot
// tell a frame offset from a moved object) or an offset beyond max_offset_m: zero.
struct ShapeRegistration {
  Eigen::Vector3d translation_model = Eigen::Vector3d::Zero();
  int pairs = 0;  // agreeing pairs (0 when not applied)
};
ShapeRegistration register_shapes(const std::vector<SurveyShape>& a,
                                  const std::vector<SurveyShape>& b, double max_offset_m,
                                  int min_pairs = 2);

// One survey's 1-sigma errors of its shapes' figures, independent of the other survey's.
struct SurveySigmas {
  double height_m = 0.0;  // the deviation noise of the survey (inspect's)
  double radius_m = 0.0;  // of a footprint radius
};

// pi r^2.
double footprint_m2(const SurveyShape& shape);

// How a kept shape grew from A to B. The height's sigma adds in quadrature both surveys'
// deviation noise and how far each top may lie beyond its highest feature; the footprint's
// propagates the radii's, d(pi r^2) = 2 pi r dr.
struct ShapeGrowth {
  double height_m = 0.0, height_sigma_m = 0.0;
  double footprint_a_m2 = 0.0, footprint_b_m2 = 0.0, footprint_sigma_m2 = 0.0;
  bool significant = false;  // |height_m| > growth_sigmas * height_sigma_m
};
ShapeGrowth shape_growth(const SurveyShape& a, const SurveyShape& b, const SurveySigmas& sigma_a,
                         const SurveySigmas& sigma_b, double growth_sigmas);

// Both surveys' shapes compared: A's moved by register_shapes, then matched (match_shapes'
// order: kept pairs nearest first, then gone, then new), each kept pair with its growth.
struct ShapeChange {
  ShapeMatch match;
  ShapeGrowth growth;  // kept pairs (match.a, match.b >= 0) only
};
struct ShapeChanges {
  ShapeRegistration registration;
  std::vector<SurveyShape> a_moved;  // A's shapes moved by registration.translation_model
  std::vector<ShapeChange> changes;
  int kept = 0, added = 0, gone = 0;
  int grown = 0;  // kept, significant and higher in B
};
ShapeChanges compare_shapes(const std::vector<SurveyShape>& a, const std::vector<SurveyShape>& b,
                            const SurveySigmas& sigma_a, const SurveySigmas& sigma_b,
                            double max_offset_m, double growth_sigmas);

}  // namespace keel::compare
