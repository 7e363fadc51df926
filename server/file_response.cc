#include "server/file_response.h"

#include "server/api_response.h"
#include "server/byte_range.h"

namespace keel::server {

namespace {

// If-None-Match: "*" or a list of entity tags; weak tags compare by their opaque part.
bool etag_matches(const std::string& header, const std::string& etag) {
  size_t pos = 0;
  while (pos < header.size()) {
    size_t comma = header.find(',', pos);
    if (comma == std::string::npos) comma = header.size();
    std::string tag = header.substr(pos, comma - pos);
    while (!tag.empty() && (tag.front() == ' ' || tag.front() == '\t')) tag.erase(0, 1);
    while (!tag.empty() && (tag.back() == ' ' || tag.back() == '\t')) tag.pop_back();
    if (tag.rfind("W/", 0) == 0) tag.erase(0, 2);
    if (tag == "*" || tag == etag) return true;
    pos = comma + 1;
  }
  return false;
}

bool is_token_safe(const std::string& name) {
  for (char c : name)
    if (c == '"' || c == '\\' || static_cast<unsigned char>(c) < 0x20) return false;
  return !name.empty();
}

}  // namespace

Response file_response(const Request& request, const StoredFile& file) {
  const std::string etag = "\"" + file.sha256 + "\"";
  Response response;
  response.headers.set("ETag", etag);
  response.headers.set("Accept-Ranges", "bytes");

  if (auto none_match = request.headers.get("If-None-Match");
      none_match && etag_matches(*none_match, etag)) {
    response.status = 304;
    return response;
  }

  ByteSpan span{0, file.size};
  response.status = 200;
  auto range = request.headers.get("Range");
  // Content never changes under an ETag here, so If-Range only fails for another tag.
  if (auto if_range = request.headers.get("If-Range"); if_range && *if_range != etag) range.reset();
  if (range) {
    RangeResult parsed = parse_range(*range, file.size);
    if (parsed.status != RangeStatus::kSatisfiable) {
      const bool malformed = parsed.status == RangeStatus::kMalformed;
      Response error = error_response(
          416, "bad_range",
          malformed
              ? "Range '" + *range + "': expected one range bytes=a-b, bytes=a- or bytes=-n"
              : "Range '" + *range + "' is outside the " + std::to_string(file.size) + " bytes");
      error.headers.set("Content-Range", unsatisfied_range_header(file.size));
      error.headers.set("ETag", etag);
      error.headers.set("Accept-Ranges", "bytes");
      return error;
    }
    span = parsed.span;
    response.status = 206;
    response.headers.set("Content-Range", content_range_header(span, file.size));
  }
  response.headers.set("Content-Type", file.content_type);
  if (is_token_safe(file.download_name))
    response.headers.set("Content-Disposition",
                         "attachment; filename=\"" + file.download_name + "\"");
  response.file = FileRegion{file.path, file.offset + span.offset, span.length};
  return response;
}

}  // namespace keel::server
