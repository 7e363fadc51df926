// Stage `ba` (seed 001, Sec. 2 and the comparison of Sec. 4): model-assisted bundle
// adjustment of a hull mission against its CAD mesh (worker/ba/model_assisted_ba.h).
//
// Keyframes are the camera's images; their initial poses are the recorded `map` keyframe poses
// correcting the recorded `odometry` (Algorithm 2 of seed 000, as the map stage does), the
// servo angle and pressure depth are interpolated at each image, and the DVL range sample
// nearest to each image (within `dvl_max_dt_s`) becomes that keyframe's Eq. (14) returns.
// Feature tracks come from the SIFT frontend on the images (`tracks=frontend`, default) or from
// the mission's ground-truth tracks listed in truth.yaml (`tracks=ground_truth`).
//
// Artifacts: `trajectory_ba.tum` (keyframe poses of the `proposed` mode, else of the last mode
// run) and `ba_solution.json` (that mode's landmarks, camera poses and x_gM, which the
// `inspect` stage reads); that mode's trajectory in the model frame added to
// `trajectories.json` as `ba`; `dvl_residuals.csv`; `cad_model.drc` (+ sidecar
// `cad_model.json`). The report has one section per mode (report_json.h).
#pragma once

#include <string>

#include "worker/pipeline/stage.h"
#include "worker/stages/ba/artifacts.h"
#include "worker/stages/ba/options.h"
#include "worker/stages/ba/report_json.h"

namespace keel::pipeline {

class BaStage : public Stage {
 public:
  std::string name() const override { return "ba"; }
  StageResult run(StageContext& context) override;  // stage.cc
  std::string report_html(const report_html::Ref& section,
                          const ReportHtmlInputs& inputs) const override;  // report_html.cc
  const OptionsSchema& options() const override;                           // options.cc
};

}  // namespace keel::pipeline
