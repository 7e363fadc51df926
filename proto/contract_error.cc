#include "proto/contract_error.h"

namespace keel::proto {

std::string json_type_name(const nlohmann::json& value) {
  if (value.is_number_integer()) return "integer";
  if (value.is_number_float()) return "number";
  return value.type_name();
}

FieldReader::FieldReader(const nlohmann::json& object, std::string path)
    : object_(object), path_(std::move(path)) {
  if (!object_.is_object()) {
    throw ContractError((path_.empty() ? std::string("document") : path_) +
                        ": expected object, got " + json_type_name(object_));
  }
}

std::string FieldReader::child(const char* field) const {
  return path_.empty() ? std::string(field) : path_ + "." + field;
}

bool FieldReader::has(const char* field) const {
  auto it = object_.find(field);
  return it != object_.end() && !it->is_null();
}

const nlohmann::json& FieldReader::at(const char* field) const {
  auto it = object_.find(field);
  if (it == object_.end() || it->is_null()) throw ContractError(child(field) + ": missing required field");
  return *it;
}

void FieldReader::reject_unknown(std::initializer_list<const char*> known) const {
  for (const auto& item : object_.items()) {
    bool found = false;
    for (const char* name : known) found = found || item.key() == name;
    if (!found) throw ContractError(child(item.key().c_str()) + ": unknown field");
  }
}

}  // namespace keel::proto
