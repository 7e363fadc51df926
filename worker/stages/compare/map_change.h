// Step 2 of the compare stage, last part: a map's change as files and figures. Every point of
// B takes its core point's M3C2 change (change_<map>.drc / .ply); the report gets the counts,
// the compared and significant areas, the distributions and the change histogram.
#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <vector>

#include "core/point_cloud.h"
#include "worker/compare/m3c2.h"
#include "worker/io/draco/draco_codec.h"
#include "worker/stages/compare/options.h"

namespace keel::pipeline {

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

}  // namespace keel::pipeline
