// What is wrong inside a ROS 2 bag's bytes (MCAP records, SQLite tables, CDR messages),
// without the file, topic or message index: the bag reader that knows them adds them.
#pragma once

#include <stdexcept>

namespace keel::io {

class BagFormatError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace keel::io
