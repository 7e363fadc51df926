// Errors of the readers and writers. Messages name the file (and line, field or topic) and
// what was expected, e.g. `imu.csv:17: column 'ax': expected a finite number, got 'nan'`.
#pragma once

#include <stdexcept>
#include <string>

namespace keel::io {

class IoError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace keel::io
