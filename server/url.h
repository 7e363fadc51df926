// Splitting a request target into path segments and query parameters (percent-decoded).
#pragma once

#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace keel::server {

struct Target {
  std::string path;                          // decoded path, "/v1/jobs/abc"
  std::vector<std::string> segments;         // {"v1", "jobs", "abc"}
  std::map<std::string, std::string> query;  // last value wins
};

// Nullopt for a target that is not origin-form ("/..."), or has a bad %-escape.
std::optional<Target> parse_target(std::string_view target);
// Decodes %XX and, when `plus_is_space`, '+' (query strings). Nullopt on a bad escape.
std::optional<std::string> percent_decode(std::string_view text, bool plus_is_space);

}  // namespace keel::server
