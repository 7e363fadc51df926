#include "worker/io/mesh/mesh_scalar_field.h"

#include <algorithm>
#include <cctype>
#include <set>
#include <stdexcept>

namespace keel::io {

void check_scalar_fields(const std::vector<ScalarField>& fields, size_t count,
                         const std::vector<std::string>& reserved_names) {
  std::set<std::string> names(reserved_names.begin(), reserved_names.end());
  for (const auto& field : fields) {
    const bool valid_name =
        !field.name.empty() && std::all_of(field.name.begin(), field.name.end(), [](char c) {
          return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
        });
    if (!valid_name) {
      throw std::invalid_argument("scalar field '" + field.name +
                                  "': expected a name of letters, digits and '_'");
    }
    if (!names.insert(field.name).second) {
      throw std::invalid_argument("scalar field '" + field.name +
                                  "': name is used twice or clashes with a built-in property");
    }
    if (field.values.size() != count) {
      throw std::invalid_argument("scalar field '" + field.name + "': has " +
                                  std::to_string(field.values.size()) + " values, expected " +
                                  std::to_string(count));
    }
  }
}

}  // namespace keel::io
