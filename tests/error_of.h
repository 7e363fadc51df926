// The message of the exception a call throws, for tests that check what an error says.
#pragma once

#include <exception>
#include <string>

namespace keel::testing {

// What `call` throws (an E; anything else propagates), "" when it returns.
template <typename E = std::exception, typename Call>
std::string error_of(const Call& call) {
  try {
    call();
  } catch (const E& e) {
    return e.what();
  }
  return "";
}

}  // namespace keel::testing
