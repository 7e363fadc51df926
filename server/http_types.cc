#include "server/http_types.h"

#include <cctype>

namespace keel::server {

bool iequals(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    if (std::tolower(static_cast<unsigned char>(a[i])) !=
        std::tolower(static_cast<unsigned char>(b[i])))
      return false;
  }
  return true;
}

void Headers::set(std::string name, std::string value) {
  for (auto& field : fields_) {
    if (iequals(field.first, name)) {
      field.second = std::move(value);
      return;
    }
  }
  add(std::move(name), std::move(value));
}

void Headers::add(std::string name, std::string value) {
  fields_.emplace_back(std::move(name), std::move(value));
}

std::optional<std::string> Headers::get(std::string_view name) const {
  for (const auto& field : fields_)
    if (iequals(field.first, name)) return field.second;
  return std::nullopt;
}

}  // namespace keel::server
