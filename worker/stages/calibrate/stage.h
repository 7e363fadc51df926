// Stage `calibrate` (issue 31; seed 000 Algorithm 3 and its automatic counterpart): for each
// candidate range sensor, the T_reference_candidate that best aligns its keyframe scans, placed
// with the refined body poses, with the reference sensor's map (robust point-to-plane over all
// keyframes jointly, mapping/extrinsic_refinement.h), its covariance and the directions the
// scene leaves unobservable. The result is offered as a reprocess with an override, never
// applied (docs/calibration.md).
//
// Artifacts: calibration.json and calibration_scans.bin (artifacts.h).
#pragma once

#include "worker/pipeline/stage.h"
#include "worker/stages/calibrate/artifacts.h"
#include "worker/stages/calibrate/options.h"

namespace keel::pipeline {

class CalibrateStage : public Stage {
 public:
  std::string name() const override { return "calibrate"; }
  StageResult run(StageContext& context) override;  // stage.cc: the numbered steps
  std::string report_html(const report_html::Ref& section,
                          const ReportHtmlInputs& inputs) const override;  // report_html.cc
  const OptionsSchema& options() const override;                           // options.cc
};

}  // namespace keel::pipeline
