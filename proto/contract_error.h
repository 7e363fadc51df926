// Strict reading of JSON contracts: every error names the field path and what was expected.
#pragma once

#include <nlohmann/json.hpp>

#include <initializer_list>
#include <stdexcept>
#include <string>

namespace keel::proto {

// Thrown when a document does not match its contract. what() names the field path.
class ContractError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Reads object fields by name and reports `path.field: expected T, got U` on mismatch.
class FieldReader {
 public:
  FieldReader(const nlohmann::json& object, std::string path);

  template <typename T>
  T required(const char* field) const {
    return convert<T>(at(field), child(field));
  }
  template <typename T>
  T optional(const char* field, T fallback) const {
    if (!has(field)) return fallback;
    return convert<T>(at(field), child(field));
  }
  bool has(const char* field) const;
  const nlohmann::json& at(const char* field) const;
  std::string child(const char* field) const;
  const std::string& path() const { return path_; }
  // Fails naming the first field that is not in `known`: a typo must not pass silently.
  void reject_unknown(std::initializer_list<const char*> known) const;

  template <typename T>
  static T convert(const nlohmann::json& value, const std::string& path);

 private:
  const nlohmann::json& object_;
  std::string path_;
};

std::string json_type_name(const nlohmann::json& value);

template <typename T>
T FieldReader::convert(const nlohmann::json& value, const std::string& path) {
  if constexpr (std::is_same_v<T, nlohmann::json>) {
    return value;
  } else if constexpr (std::is_same_v<T, bool>) {
    if (!value.is_boolean()) throw ContractError(path + ": expected boolean, got " + json_type_name(value));
    return value.get<bool>();
  } else if constexpr (std::is_integral_v<T>) {
    if (!value.is_number_integer())
      throw ContractError(path + ": expected integer, got " + json_type_name(value));
    return value.get<T>();
  } else if constexpr (std::is_floating_point_v<T>) {
    if (!value.is_number()) throw ContractError(path + ": expected number, got " + json_type_name(value));
    return value.get<T>();
  } else if constexpr (std::is_same_v<T, std::string>) {
    if (!value.is_string()) throw ContractError(path + ": expected string, got " + json_type_name(value));
    return value.get<std::string>();
  } else if constexpr (std::is_same_v<T, std::vector<std::string>>) {
    if (!value.is_array()) throw ContractError(path + ": expected array of strings, got " + json_type_name(value));
    std::vector<std::string> out;
    for (size_t i = 0; i < value.size(); ++i)
      out.push_back(convert<std::string>(value[i], path + "[" + std::to_string(i) + "]"));
    return out;
  } else {
    // Contract structs provide `static T from_json(const nlohmann::json&, const std::string& path)`.
    return T::from_json(value, path);
  }
}

}  // namespace keel::proto
