// The stages built into this worker. Adding a stage is one line in `entries` below (in
// pipeline order) plus its source file in CMakeLists.txt.
#include <stdexcept>
#include <string>
#include <vector>

#include "worker/pipeline/ba_stage.h"
#include "worker/pipeline/compare_stage.h"
#include "worker/pipeline/ingest_stage.h"
#include "worker/pipeline/inspect_stage.h"
#include "worker/pipeline/map_stage.h"
#include "worker/pipeline/refine_stage.h"
#include "worker/pipeline/stage.h"

namespace keel::pipeline {

namespace {

struct StageEntry {
  const char* name;
  std::unique_ptr<Stage> (*make)();
};

const std::vector<StageEntry>& entries() {
  static const std::vector<StageEntry> table = {
      {"ingest", make_ingest_stage},
      {"refine", make_refine_stage},
      {"map", make_map_stage},
      {"ba", make_ba_stage},
      {"inspect", make_inspect_stage},
      {"compare", make_compare_stage},
  };
  return table;
}

}  // namespace

std::unique_ptr<Stage> make_stage(const std::string& name) {
  for (const auto& entry : entries())
    if (name == entry.name) return entry.make();
  std::string known;
  for (const auto& entry : entries())
    known += (known.empty() ? "" : ", ") + std::string(entry.name);
  throw std::invalid_argument("unknown stage '" + name +
                              "' (this worker has: " + (known.empty() ? "none" : known) + ")");
}

std::vector<std::string> available_stages() {
  std::vector<std::string> names;
  for (const auto& entry : entries()) names.emplace_back(entry.name);
  return names;
}

}  // namespace keel::pipeline
