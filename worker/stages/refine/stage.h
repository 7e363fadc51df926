// Stage `refine` (seed 000 Sec. III-V): the recorded keyframe (`map`) poses refined by a batch
// factor graph that couples the recorded odometry (or GICP between keyframe scans when the
// mission has none), loop closures, IMU and DVL preintegration (worker/slam/refine_solver.h).
// Writes `trajectory_refined.tum` (one pose per keyframe, the keyframes' exact stamps) and its
// section of report.json; with ground truth, ATE/RPE of the MAP poses and of the refinement
// without and with DVL fusion, side by side as seed 000 Table II.
#pragma once

#include "worker/pipeline/stage.h"
#include "worker/stages/refine/artifacts.h"
#include "worker/stages/refine/options.h"

namespace keel::pipeline {

class RefineStage : public Stage {
 public:
  std::string name() const override { return "refine"; }
  StageResult run(StageContext& context) override;  // stage.cc: the numbered steps
  std::string report_html(const report_html::Ref& section,
                          const ReportHtmlInputs& inputs) const override;  // report_html.cc
  const OptionsSchema& options() const override;                           // options.cc
};

}  // namespace keel::pipeline
