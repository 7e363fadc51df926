// The error body every non-2xx API response carries: {"error": {"code", "message"}}.
#pragma once

#include <nlohmann/json.hpp>

#include <string>

namespace keel::proto {

struct ApiError {
  std::string code;     // machine-readable, snake_case: "not_found", "sha256_mismatch", ...
  std::string message;  // for people: names the field, file or id that is wrong

  nlohmann::json to_json() const;
  static ApiError from_json(const nlohmann::json& body, const std::string& path = "");
};

}  // namespace keel::proto
