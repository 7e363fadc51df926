// A named per-vertex (or per-point) scalar such as `deviation` or `density`, carried by the
// PLY writers and the Draco encoder.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace keel::io {

struct ScalarField {
  std::string name;           // PLY property / Draco attribute name: [A-Za-z0-9_]+
  std::vector<float> values;  // one per vertex or point
};

// Throws std::invalid_argument naming the field when its name is not [A-Za-z0-9_]+, is
// repeated or reserved (x, y, z ...), or when it has not `count` values.
void check_scalar_fields(const std::vector<ScalarField>& fields, size_t count,
                         const std::vector<std::string>& reserved_names);

}  // namespace keel::io
