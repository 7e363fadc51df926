#include "worker/compare/shape_matching.h"

#include <algorithm>
#include <cmath>

namespace keel::compare {
namespace {

// A's shapes moved by `t`.
std::vector<SurveyShape> shifted(std::vector<SurveyShape> shapes, const Eigen::Vector3d& t) {
  for (SurveyShape& shape : shapes) shape.centroid_model += t;
  return shapes;
}

}  // namespace

std::vector<ShapeMatch> match_shapes(const std::vector<SurveyShape>& a,
                                     const std::vector<SurveyShape>& b) {
  std::vector<ShapeMatch> candidates;
  for (size_t i = 0; i < a.size(); ++i)
    for (size_t j = 0; j < b.size(); ++j) {
      const double d = (a[i].centroid_model - b[j].centroid_model).norm();
      if (d < a[i].radius_m + b[j].radius_m) candidates.push_back({int(i), int(j), d});
    }
  std::sort(candidates.begin(), candidates.end(),
            [](const ShapeMatch& x, const ShapeMatch& y) { return x.distance_m < y.distance_m; });
  std::vector<bool> used_a(a.size(), false), used_b(b.size(), false);
  std::vector<ShapeMatch> out;
  for (const ShapeMatch& m : candidates) {
    if (used_a[m.a] || used_b[m.b]) continue;
    used_a[m.a] = used_b[m.b] = true;
    out.push_back(m);
  }
  for (size_t i = 0; i < a.size(); ++i)
    if (!used_a[i]) out.push_back({int(i), -1, 0.0});
  for (size_t j = 0; j < b.size(); ++j)
    if (!used_b[j]) out.push_back({-1, int(j), 0.0});
  return out;
}

ShapeRegistration register_shapes(const std::vector<SurveyShape>& a,
                                  const std::vector<SurveyShape>& b, double max_offset_m,
                                  int min_pairs) {
  ShapeRegistration best;
  double best_norm = 0.0;
  for (const SurveyShape& sa : a)
    for (const SurveyShape& sb : b) {
      const Eigen::Vector3d candidate = sb.centroid_model - sa.centroid_model;
      if (candidate.norm() > max_offset_m) continue;
      std::vector<ShapeMatch> agreeing;
      for (const ShapeMatch& m : match_shapes(shifted(a, candidate), b))
        if (m.a >= 0 && m.b >= 0) agreeing.push_back(m);
      const int pairs = static_cast<int>(agreeing.size());
      // The most pairs; among equals the smaller offset (no evidence for moving further).
      if (pairs < best.pairs || (pairs == best.pairs && candidate.norm() >= best_norm)) continue;
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (const ShapeMatch& m : agreeing) mean += b[m.b].centroid_model - a[m.a].centroid_model;
      best.pairs = pairs;
      best.translation_model = mean / pairs;
      best_norm = candidate.norm();
    }
  if (best.pairs < min_pairs || best.translation_model.norm() > max_offset_m) return {};
  return best;
}

double footprint_m2(const SurveyShape& shape) { return M_PI * shape.radius_m * shape.radius_m; }

ShapeGrowth shape_growth(const SurveyShape& a, const SurveyShape& b, const SurveySigmas& sigma_a,
                         const SurveySigmas& sigma_b, double growth_sigmas) {
  ShapeGrowth g;
  g.height_m = b.height_m - a.height_m;
  g.height_sigma_m = std::hypot(std::hypot(sigma_a.height_m, sigma_b.height_m),
                                std::hypot(a.height_sampling_sigma_m, b.height_sampling_sigma_m));
  g.footprint_a_m2 = footprint_m2(a);
  g.footprint_b_m2 = footprint_m2(b);
  g.footprint_sigma_m2 = std::hypot(2 * M_PI * a.radius_m * sigma_a.radius_m,
                                    2 * M_PI * b.radius_m * sigma_b.radius_m);
  g.significant = std::abs(g.height_m) > growth_sigmas * g.height_sigma_m;
  return g;
}

ShapeChanges compare_shapes(const std::vector<SurveyShape>& a, const std::vector<SurveyShape>& b,
                            const SurveySigmas& sigma_a, const SurveySigmas& sigma_b,
                            double max_offset_m, double growth_sigmas) {
  ShapeChanges out;
  out.registration = register_shapes(a, b, max_offset_m);
  out.a_moved = shifted(a, out.registration.translation_model);
  for (const ShapeMatch& m : match_shapes(out.a_moved, b)) {
    ShapeChange change{m, {}};
    if (m.a >= 0 && m.b >= 0) {
      change.growth = shape_growth(out.a_moved[m.a], b[m.b], sigma_a, sigma_b, growth_sigmas);
      ++out.kept;
      out.grown += change.growth.significant && change.growth.height_m > 0;
    } else if (m.b >= 0) {
      ++out.added;
    } else {
      ++out.gone;
    }
    out.changes.push_back(change);
  }
  return out;
}

}  // namespace keel::compare
