#include "worker/pipeline/stage_options.h"

#include <algorithm>

#include "proto/contract_error.h"

namespace keel::pipeline {

std::string join_names(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

void check_stage_options(const nlohmann::json& options, const std::string& stage,
                         const std::vector<std::string>& known) {
  if (options.is_null()) return;
  if (!options.is_object())
    throw proto::ContractError("options." + stage + ": expected an object, got " +
                               proto::json_type_name(options));
  for (const auto& item : options.items())
    if (std::find(known.begin(), known.end(), item.key()) == known.end())
      throw proto::ContractError("options." + stage + "." + item.key() +
                                 ": unknown option (known: " + join_names(known) + ")");
}

}  // namespace keel::pipeline
