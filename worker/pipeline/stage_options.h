// Shared reading of a stage's JSON options (`--set stage.option=value`). Being replaced by
// option_table.h, stage by stage; removed once every stage has its table.
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "proto/contract_error.h"
#include "worker/pipeline/option_table.h"

namespace keel::pipeline {

// Reads `options.<stage>` (an object) and remembers every option name asked for, so the
// list of known options is the reading code itself. `finish()` then fails on a key that
// was never asked for: a typo fails with "options.<stage>.<key>: unknown option (known:
// ...)" instead of being ignored.
class StageOptionReader {
 public:
  StageOptionReader(const nlohmann::json& options, const std::string& stage);

  template <typename T>
  T optional(const char* name, T fallback) {
    asked_.emplace_back(name);
    return reader_.optional<T>(name, fallback);
  }
  bool has(const char* name) {
    asked_.emplace_back(name);
    return reader_.has(name);
  }
  const nlohmann::json& at(const char* name) { return reader_.at(name); }

  void finish() const;

 private:
  const nlohmann::json& options_;
  proto::FieldReader reader_;
  std::vector<std::string> asked_;
};

}  // namespace keel::pipeline
