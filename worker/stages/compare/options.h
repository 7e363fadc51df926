// The compare stage's options (`--set compare.<name>=<value>`) and their table (options.cc):
// from_json, to_json and docs/stage-options.md's table are made from it.
#pragma once

#include <string>
#include <vector>

#include "worker/compare/m3c2.h"
#include "worker/compare/stable_registration.h"
#include "worker/compare/tile_correction.h"
#include "worker/pipeline/option_table.h"

namespace keel::pipeline {

struct CompareStageOptions {
  // Set by the server on a compare job (POST /v1/comparisons); the jobs come as input_jobs.
  std::string job_a, job_b;
  // Maps compared; empty = `combined` when both jobs have it, else every sensor map both have.
  std::vector<std::string> sensors;
  bool register_maps = true;  // false: B's maps are taken as already in A's frame
  compare::StableRegistrationOptions registration;
  // Piecewise registration after the global one (compare/local_registration.h): tiles of this
  // side; 0 turns it off.
  double local_registration_tile_m = 10.0;
  // Which structure of a tile is stable, and when its correction is applied; its stable
  // structure also gives the tile's `reg` (compare/tile_correction.h).
  compare::TileCorrectionOptions tile_correction;
  compare::M3c2Options m3c2;
  // reg of Lague et al.'s Eq. (1): < 0 (the default) measures it per tile of
  // local_registration_tile_m (the whole map without tiles) on the tile's stable structure,
  // calibrated so that LoD95 holds 95 % there (compare/tile_correction.h); a number >= 0 is
  // taken for every core point.
  double registration_error_m = -1.0;
  // A core's change is significant only when at least half the core points within this radius
  // exceed LoD95 with its sign (compare/coherent_change.h); 0: beyond LoD95 alone.
  double significance_radius_m = 0.15;
  // The z at which a core's change is significant, its reg calibrated to that confidence as
  // LoD95's is to 95 %: 2.576 (99 %) leaves ~1 % of unchanged structure significant where the
  // 95 % level would leave 5 %.
  double significance_z = 2.576;
  int histogram_bins = 40;
  double histogram_range_m = 0.2;  // the change histogram spans +-this
  int draco_position_bits = 18;
  int draco_field_bits = 14;
  // 5, as the map stage: the single-threaded encode is the stage's critical path; level 7
  // makes files a quarter smaller in more than twice the time, the decoded values the same.
  int draco_compression_level = 5;
  bool write_ply = true;
  // Hulls: a shape is significant growth when |growth| exceeds this many sigmas (1.96: 95 %).
  double growth_sigmas = 1.96;
  // Hulls: the largest frame offset between the surveys' shapes that matching corrects
  // (compare::register_shapes); 0 = match the shapes where each survey's x_gM put them.
  double shape_max_offset_m = 1.0;
  int threads = 2;
};

// Fails (ContractError) naming the option, and listing the known ones for an unknown name.
const OptionTable<CompareStageOptions>& compare_option_table();

}  // namespace keel::pipeline
