#include "worker/stages/ingest/options.h"

namespace keel::pipeline {
namespace {

// "expected > bound", the stage's words (greater_than's say "a number > bound").
Check<double> above(double bound) {
  return [bound](const double& v) {
    return v > bound ? std::string() : "expected > " + number_text(bound);
  };
}

}  // namespace

const OptionTable<IngestOptions>& ingest_option_table() {
  static const OptionTable<IngestOptions> table(
      "ingest",
      {
          option("gap_factor", &IngestOptions::gap_factor, above(1.0),
                 OptionDoc{"",
                           "> 1. A gap is an interval between consecutive stamps longer than "
                           "`gap_factor` nominal periods (`gap_factor / rate_hz` s, `rate_hz` "
                           "from mission.yaml); gaps are counted and warned about (sensors "
                           "with a nominal `rate_hz` only)",
                           "", "", ""}),
          option("rate_tolerance", &IngestOptions::rate_tolerance, above(0.0),
                 OptionDoc{"",
                           "> 0. Warn when the measured rate differs from the nominal one by "
                           "more than this fraction of it (0.2 = 20 %)",
                           "", "", ""}),
      });
  return table;
}

}  // namespace keel::pipeline
