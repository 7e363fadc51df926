// The ingest stage's options (`--set ingest.<name>=<value>`) and their table (options.cc):
// from_json, to_json and docs/stage-options.md's table are made from it.
#pragma once

#include "worker/pipeline/option_table.h"

namespace keel::pipeline {

// Not in either paper: how the bundle's streams are judged against mission.yaml's rates.
struct IngestOptions {
  double gap_factor = 2.5;      // a gap is an interval longer than gap_factor nominal periods
  double rate_tolerance = 0.2;  // measured rate off nominal by more than this: a warning
};

// Fails (ContractError) naming the option, and listing the known ones for an unknown name.
const OptionTable<IngestOptions>& ingest_option_table();

}  // namespace keel::pipeline
