#include "proto/api_error.h"

#include "proto/contract_error.h"

namespace keel::proto {

nlohmann::json ApiError::to_json() const {
  return {{"error", {{"code", code}, {"message", message}}}};
}

ApiError ApiError::from_json(const nlohmann::json& body, const std::string& path) {
  FieldReader top(body, path);
  FieldReader error(top.at("error"), top.child("error"));
  return {error.required<std::string>("code"), error.required<std::string>("message")};
}

}  // namespace keel::proto
