// Step 3 of the compare stage: hulls. Both remeshed hulls come from the same CAD model, so they
// are compared in the model frame (each job's mesh moved back by its own x_gM): each vertex of
// B takes the deviation of A's nearest vertex, and the shapes of both shapes.json are matched
// by overlap into changes.json (new, gone, and the growth of each kept shape).
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

#include "worker/stages/compare/stage.h"

namespace keel::pipeline {

// True when `dir` holds what a hull comparison reads: mesh_remeshed.drc, shapes.json and
// ba_solution.json.
bool has_hull_products(const std::filesystem::path& dir);

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

// Writes change_hull.drc / .ply and returns the report section (the changes.json document).
nlohmann::json compare_hulls(StageContext& context, const CompareStageOptions& options,
                             std::vector<std::string>* artifacts);

}  // namespace keel::pipeline
