// The stages built into this worker: one entry per name of proto/stages.h, in pipeline order.
#include <stdexcept>
#include <string>
#include <vector>

#include "worker/pipeline/option_table.h"
#include "worker/pipeline/stage.h"

namespace keel::pipeline {

namespace {

struct StageEntry {
  const char* name;
  std::unique_ptr<Stage> (*make)();
};

const std::vector<StageEntry>& entries() {
#define KEEL_STAGE_ENTRY(name) {#name, make_##name##_stage},
  static const std::vector<StageEntry> table = {KEEL_STAGES(KEEL_STAGE_ENTRY)};
#undef KEEL_STAGE_ENTRY
  return table;
}

}  // namespace

std::unique_ptr<Stage> make_stage(const std::string& name) {
  for (const auto& entry : entries())
    if (name == entry.name) return entry.make();
  std::vector<std::string> known;
  for (const auto& entry : entries()) known.emplace_back(entry.name);
  throw std::invalid_argument("unknown stage '" + name + "' (this worker has: " +
                              (known.empty() ? "none" : join_names(known)) + ")");
}

std::vector<std::string> available_stages() {
  std::vector<std::string> names;
  for (const auto& entry : entries()) names.emplace_back(entry.name);
  return names;
}

}  // namespace keel::pipeline
