// Stage `inspect` (seed 001, Sec. 3): model-assisted visual mapping from the `ba` stage's
// solution (ba_solution.json: landmarks with h and lambda, camera poses, x_gM). The CAD mesh is
// moved into the world frame by x_gM, shapes are detected per view (Algorithm 1) and fused into
// the prior (Algorithm 2, Eq. 15) by keel::inspect::run_inspect.
//
// Artifacts (world frame, the CAD moved by x_gM): mesh_remeshed.drc (Draco, per-vertex
// `deviation` in m) with its sidecar mesh_remeshed.json, mesh_remeshed.ply (same field) and
// shapes.json (keel::inspect::shapes_to_json). Report: the shapes with their heights, extents
// and views and, when truth.yaml lists foreign_objects, each object matched to the nearest shape
// (found / missed, measured vs true height) and the count of shapes matching no object.
#pragma once

#include <string>

#include "worker/pipeline/stage.h"
#include "worker/stages/inspect/artifacts.h"
#include "worker/stages/inspect/options.h"

namespace keel::pipeline {

class InspectStage : public Stage {
 public:
  std::string name() const override { return "inspect"; }
  StageResult run(StageContext& context) override;  // stage.cc
  std::string report_html(const report_html::Ref& section,
                          const ReportHtmlInputs& inputs) const override;  // report_html.cc
  const OptionsSchema& options() const override;                           // options.cc
};

}  // namespace keel::pipeline
