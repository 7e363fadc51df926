// Answers for content-addressed bytes (GET /v1/blobs/{sha}, GET /v1/artifacts/{id}):
// strong ETag = the SHA-256, If-None-Match -> 304, a single Range -> 206, 416 otherwise.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

#include "server/http_types.h"

namespace keel::server {

struct StoredFile {
  std::filesystem::path path;
  uint64_t size = 0;
  uint64_t offset = 0;  // where the served bytes start in `path` (a member of a tar)
  std::string sha256;   // the ETag's value
  std::string content_type = "application/octet-stream";
  std::string download_name;  // for Content-Disposition, "" = none
};

Response file_response(const Request& request, const StoredFile& file);

}  // namespace keel::server
