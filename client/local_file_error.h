// A problem with a local file (missing mission folder, unreadable file, unsafe symlink,
// bad config file): `keel` exits with code 6 for it.
#pragma once

#include <stdexcept>

namespace keel::client {

class LocalFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace keel::client
