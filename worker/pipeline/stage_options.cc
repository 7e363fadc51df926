#include "worker/pipeline/stage_options.h"

#include <algorithm>

namespace keel::pipeline {

StageOptionReader::StageOptionReader(const nlohmann::json& options, const std::string& stage)
    : options_(options), reader_(options, "options." + stage) {}

void StageOptionReader::finish() const {
  for (const auto& item : options_.items()) {
    if (std::find(asked_.begin(), asked_.end(), item.key()) != asked_.end()) continue;
    std::vector<std::string> known;
    for (const auto& name : asked_)
      if (std::find(known.begin(), known.end(), name) == known.end()) known.push_back(name);
    throw proto::ContractError(reader_.child(item.key().c_str()) +
                               ": unknown option (known: " + join_names(known) + ")");
  }
}

}  // namespace keel::pipeline
