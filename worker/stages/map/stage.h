// Stage `map` (seed 000 Sec. VI): the dense inspection map, decoupled from SLAM. Every scan of
// every lidar and sonar is streamed through MapBuilder (deskew with the TF tree, the filters of
// Table IV, intermediary maps of N_I scans, final filters) with poses from the chain of
// Sec. VI-C: keyframe poses (`trajectory_refined.tum` of an earlier `refine` stage, else the
// recorded `map` poses) correcting the recorded high-rate `odometry` by Algorithm 2, so every
// scan gets a pose. The first lidar's keyframe scans also build the SLAM-map baseline, and the
// report compares both maps by the metrics of Eqs. (23)-(26), as Table V does.
//
// Artifacts: map_<sensor>.drc / .ply / tiles_<sensor>.tar per sensor, and the same for the
// combined map (Eq. (21), each point with its `sensor`). The maps are kept out of core, in tiles
// within map.memory_budget_mb (tiled_maps.h); a map too large for the budget has no single
// Draco file. Each .drc has its sidecar map_<sensor>.json, and a map larger than
// preview_max_points map_<sensor>_preview.drc with its own sidecar (map_outputs.h).
#pragma once

#include "worker/pipeline/stage.h"
#include "worker/stages/map/artifacts.h"
#include "worker/stages/map/options.h"

namespace keel::pipeline {

class MapStage : public Stage {
 public:
  std::string name() const override { return "map"; }
  StageResult run(StageContext& context) override;  // stage.cc: the numbered steps
  std::string report_html(const report_html::Ref& section,
                          const ReportHtmlInputs& inputs) const override;  // report_html.cc
  const OptionsSchema& options() const override;                           // options.cc
};

}  // namespace keel::pipeline
