// Step 2 of the compare stage: maps (compare_maps.cc), in three parts:
//   - alignment (map_alignment.cc): B's maps moved into A's frame. The global registration on
//     stable structure runs once, on the first map compared, and its transform moves every map
//     of B; then, with tiles, each tile of B is registered on its own
//     (compare/local_registration.h), two surveys' maps each carrying their own trajectory's
//     errors;
//   - measurement: every point of each map of B gets its C2C distance to A and the M3C2 change
//     (with its 95 % level of detection) of its core point;
//   - the change as files and figures (map_change.cc): change_<map>.drc / .ply, where every
//     point of B holds its core point's change, and the report's counts, areas, distributions
//     and change histogram.
#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "core/point_cloud.h"
#include "core/pose.h"
#include "worker/compare/local_registration.h"
#include "worker/compare/m3c2.h"
#include "worker/io/draco/draco_codec.h"
#include "worker/pipeline/stage.h"
#include "worker/stages/compare/options.h"

namespace keel::pipeline {

// Compares the maps, writes their artifacts into context.work_dir (names appended to
// `artifacts`) and returns the report section {"registration": ..., "maps": {name: ...}}.
nlohmann::json compare_maps(StageContext& context, const CompareStageOptions& options,
                            const std::vector<std::string>& maps,
                            std::vector<std::string>* artifacts);

struct MapAlignment {
  bool registered = false;
  Pose3 T_a_b = Pose3::Identity();  // maps B's points into A's frame
  nlohmann::json registration;      // the report's "registration", once registered
};

// Moves `b` onto `a` (nothing with options.register_maps false); returns the map's
// "local_registration" section, null without it.
nlohmann::json align_map(StageContext& context, const CompareStageOptions& options,
                         const std::string& map, const std::vector<Eigen::Vector3f>& a,
                         std::vector<Eigen::Vector3f>* b, MapAlignment* alignment);

// The local registration's options from the stage's.
compare::LocalRegistrationOptions local_registration_options(StageContext& context,
                                                             const CompareStageOptions& options);

// B's points with their change: where a core point's change is undefined its points hold the
// attribute's no_data (docs/artifacts.md), so a viewer tells "unmeasured" from "unchanged".
struct ChangeCloud {
  PointCloud cloud;
  io::PartsAttributes attributes;  // m3c2_m, lod95_m, significant (-1: undefined), c2c_m
};
ChangeCloud change_cloud(const std::vector<compare::CoreChange>& changes,
                         const std::vector<uint32_t>& core_of, const std::vector<float>& c2c,
                         std::vector<Eigen::Vector3f> points);

// The report's figures of the change: counts, areas, distributions, the change histogram.
nlohmann::json change_figures(const std::vector<compare::CoreChange>& changes,
                              const std::vector<float>& c2c, const CompareStageOptions& options);

// How the level of detection holds: each tile's `reg`, and on the stable structure (where no
// change is expected) the fraction of core points whose |M3C2| exceeds LoD95: 5 % when the
// 95 % level means 95 %.
nlohmann::json level_of_detection(const std::vector<compare::CoreChange>& changes,
                                  const std::vector<char>& stable,
                                  const std::vector<double>& registration_error_m,
                                  const std::vector<compare::TileError>& tiles,
                                  const CompareStageOptions& options);

}  // namespace keel::pipeline
