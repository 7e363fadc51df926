// Options of stage `inspect` (`--set inspect.<name>=<value>`), read, written and documented by
// one table (options.cc, docs/stage-options.md "inspect").
#pragma once

#include <nlohmann/json.hpp>

#include "worker/inspect/inspect_options.h"

namespace keel::pipeline {

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
