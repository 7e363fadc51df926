// Stage `compare` (issue 16): what changed between two finished jobs of the same structure,
// A (earlier) and B (later), given as StageContext::input_jobs. As numbered steps:
//   1. options (--set compare.x=v); what the jobs hold decides what is compared: maps (both
//      have map_<sensor>.drc), hulls (both have mesh_remeshed.drc, shapes.json and
//      ba_solution.json); a map job against a hull job, or jobs with nothing in common, are
//      refused with the reason;
//   2. maps: B registered onto A on stable structure (compare/stable_registration.h), then per
//      map the C2C distance of every point of B and its M3C2 change with the 95 % level of
//      detection (compare/m3c2.h): change_<sensor>.drc / .ply;
//   3. hulls: the x_gM difference, each vertex's deviation in B minus A (change_hull.drc /
//      .ply, model frame), shapes matched by overlap in the model frame: new, gone, and the
//      height and footprint growth of each shape kept, with uncertainties (changes.json);
//   4. runs: every figure of A's and B's report.json side by side with its difference, the
//      options that differ and, with both refined trajectories, B's ATE against A's.
#pragma once

#include <nlohmann/json.hpp>

#include <memory>
#include <string>
#include <vector>

#include "worker/compare/m3c2.h"
#include "worker/compare/stable_registration.h"
#include "worker/pipeline/stage.h"
#include "worker/stages/compare/artifacts.h"

namespace keel::pipeline {

// `--set compare.<name>=<value>`.
struct CompareStageOptions {
  // Maps compared; empty = `combined` when both jobs have it, else every sensor map both have.
  std::vector<std::string> sensors;
  bool register_maps = true;  // false: B's maps are taken as already in A's frame
  compare::StableRegistrationOptions registration;
  // Piecewise registration after the global one (compare/local_registration.h): tiles of this
  // side; 0 turns it off.
  double local_registration_tile_m = 10.0;
  compare::M3c2Options m3c2;
  // reg of Lague et al.'s Eq. (1), assumed uniform over the structure as they do: < 0 (the
  // default) takes 1.4826 x the median absolute M3C2 distance of all core points after
  // registration, the spread of the measured change over the whole structure, which real
  // changes (a small part of a structure) do not move; a number >= 0 overrides it.
  double registration_error_m = -1.0;
  int histogram_bins = 40;
  double histogram_range_m = 0.2;  // the change histogram spans +-this
  int draco_position_bits = 18;
  int draco_field_bits = 14;
  // 5, as the map stage: on the 220 s bridge's change map (10.9 M points, 4 fields) the
  // single-threaded encode, the stage's critical path, takes 5.4 CPU s instead of 12.6 s at 7,
  // for a file 38 % larger (63.9 vs 46.2 MB); the decoded values are the same.
  int draco_compression_level = 5;
  bool write_ply = true;
  // Hulls: a shape is significant growth when |growth| exceeds this many sigmas (1.96: 95 %).
  double growth_sigmas = 1.96;
  // Hulls: the largest frame offset between the surveys' shapes that matching corrects
  // (register_shapes); 0 = match the shapes where each survey's x_gM put them.
  double shape_max_offset_m = 1.0;
  int threads = 2;

  // Fails (ContractError) naming the option, and listing the known ones for an unknown name.
  static CompareStageOptions from_json(const nlohmann::json& options);
};

}  // namespace keel::pipeline
