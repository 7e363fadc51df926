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

#include <nlohmann/json.hpp>

#include <memory>
#include <string>
#include <vector>

#include "worker/inspect/inspect_options.h"
#include "worker/pipeline/stage.h"
#include "worker/stages/inspect/artifacts.h"

namespace keel::pipeline {

// `--set inspect.<name>=<value>`.
struct InspectStageOptions {
  inspect::InspectOptions inspect;  // tau_m, dbscan_eps_m, ... (paper defaults)
  // Draco: 16 bits keep the quantization error <= sqrt(3)/2 * 30 m / (2^16 - 1) = 0.4 mm on a
  // 30 m hull; the deviation field at 12 bits.
  int draco_position_bits = 16;
  int draco_field_bits = 12;
  bool write_ply = true;
  // Evaluation against truth.yaml: a shape matches a foreign object when its centroid lies
  // within the object's radius plus this distance of the object's centre.
  double match_distance_m = 0.3;

  // Fails (ContractError) naming the option, and listing the known ones for an unknown name.
  static InspectStageOptions from_json(const nlohmann::json& options);
};

}  // namespace keel::pipeline
