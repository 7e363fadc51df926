// The server's own small HTTP request/response types. The pure handler (http_handler.h and
// the route files) works on these instead of Beast's message types so that it, its tests and
// everything that includes it compile without Beast/Asio (the heavy headers stay in the
// socket-side files: http_server.cc and file_region_body.h).
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace keel::server {

// Header fields in arrival order; names compare case-insensitively.
class Headers {
 public:
  void set(std::string name, std::string value);  // replaces an existing field
  void add(std::string name, std::string value);  // keeps existing fields
  // The first value of `name`, or nullopt.
  std::optional<std::string> get(std::string_view name) const;
  bool has(std::string_view name) const { return get(name).has_value(); }
  const std::vector<std::pair<std::string, std::string>>& fields() const { return fields_; }

 private:
  std::vector<std::pair<std::string, std::string>> fields_;
};

bool iequals(std::string_view a, std::string_view b);

struct Request {
  std::string method;  // "GET", "PUT", ...
  std::string target;  // origin-form: "/v1/jobs?state=queued"
  Headers headers;
  std::string body;
};

// Bytes [offset, offset + length) of a file, streamed by the socket side.
struct FileRegion {
  std::filesystem::path path;
  uint64_t offset = 0;
  uint64_t length = 0;
};

struct Response {
  int status = 200;
  Headers headers;
  std::string body;                // used when `file` is empty
  std::optional<FileRegion> file;  // a file region to stream instead of `body`
};

}  // namespace keel::server
