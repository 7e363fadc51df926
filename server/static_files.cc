#include "server/static_files.h"

#include <openssl/evp.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <fstream>
#include <iterator>
#include <sstream>

#include "server/api_response.h"

namespace keel::server {

namespace fs = std::filesystem;

namespace {

struct MimeEntry {
  const char* extension;
  const char* type;
};

// What the dashboard serves; module scripts must be text/javascript (HTML spec) and
// WebAssembly.instantiateStreaming needs application/wasm.
constexpr MimeEntry kMimeTypes[] = {
    {"html", "text/html; charset=utf-8"},
    {"js", "text/javascript; charset=utf-8"},
    {"mjs", "text/javascript; charset=utf-8"},
    {"css", "text/css; charset=utf-8"},
    {"json", "application/json"},
    {"map", "application/json"},
    {"wasm", "application/wasm"},
    {"svg", "image/svg+xml"},
    {"png", "image/png"},
    {"ico", "image/x-icon"},
    {"txt", "text/plain; charset=utf-8"},
    {"woff2", "font/woff2"},
};

constexpr const char* kImmutable = "public, max-age=31536000, immutable";

std::string lowercase(std::string_view text) {
  std::string out(text);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::string base64_sha256(std::string_view bytes) {
  std::array<unsigned char, EVP_MAX_MD_SIZE> digest{};
  unsigned int length = 0;
  EVP_Digest(bytes.data(), bytes.size(), digest.data(), &length, EVP_sha256(), nullptr);
  std::string out(4 * ((length + 2) / 3) + 1, '\0');
  const int written = EVP_EncodeBlock(reinterpret_cast<unsigned char*>(out.data()), digest.data(),
                                      static_cast<int>(length));
  out.resize(static_cast<size_t>(written));
  return out;
}

// A segment that could name something outside its folder once joined to a path.
bool unsafe_segment(const std::string& segment) {
  if (segment == "." || segment == "..") return true;
  for (char c : segment)
    if (c == '/' || c == '\\' || c == '\0') return true;
  return false;
}

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// Weak validator for files that change only when the build copies them again.
std::string file_etag(const fs::path& path, uint64_t size) {
  std::error_code ec;
  const auto mtime = fs::last_write_time(path, ec).time_since_epoch().count();
  std::ostringstream out;
  out << "W/\"" << std::hex << size << '-' << mtime << '"';
  return out.str();
}

bool etag_listed(const std::string& header, const std::string& etag) {
  const std::string opaque = etag.substr(2);  // without "W/"
  return header == "*" || header.find(opaque) != std::string::npos;
}

Response not_found(const std::string& what) { return error_response(404, "not_found", what); }

void set_security_headers(Response& response, const std::string& csp) {
  response.headers.set("Content-Security-Policy", csp);
  response.headers.set("X-Content-Type-Options", "nosniff");
  response.headers.set("Referrer-Policy", "no-referrer");
  response.headers.set("X-Frame-Options", "DENY");
  response.headers.set("Cross-Origin-Opener-Policy", "same-origin");
}

}  // namespace

std::string mime_type_for_extension(std::string_view extension) {
  const std::string lower = lowercase(extension);
  for (const MimeEntry& entry : kMimeTypes)
    if (lower == entry.extension) return entry.type;
  return "application/octet-stream";
}

std::vector<std::string> inline_script_hashes(std::string_view html) {
  std::vector<std::string> hashes;
  const std::string lower = lowercase(html);
  size_t pos = 0;
  while ((pos = lower.find("<script", pos)) != std::string::npos) {
    const size_t tag_end = lower.find('>', pos);
    if (tag_end == std::string::npos) break;
    const std::string_view tag(lower.data() + pos, tag_end - pos);
    const size_t close = lower.find("</script", tag_end);
    if (close == std::string::npos) break;
    // CSP hashes the element's text exactly as it is in the file.
    if (tag.find(" src=") == std::string_view::npos && tag.find(" src ") == std::string_view::npos)
      hashes.push_back("'sha256-" + base64_sha256(html.substr(tag_end + 1, close - tag_end - 1)) +
                       "'");
    pos = close;
  }
  return hashes;
}

std::string content_security_policy(const std::vector<std::string>& script_hashes) {
  std::string script_src = "'self' 'wasm-unsafe-eval'";
  for (const auto& hash : script_hashes) script_src += " " + hash;
  return "default-src 'none'; script-src " + script_src +
         "; worker-src blob:; connect-src 'self'; img-src 'self' data: blob:; "
         "style-src 'self'; font-src 'self'; manifest-src 'self'; base-uri 'none'; "
         "form-action 'none'; frame-ancestors 'none'";
}

StaticFiles::StaticFiles(fs::path root) : root_(std::move(root)) {
  std::error_code ec;
  const fs::path canonical = fs::canonical(root_, ec);
  if (!ec) root_ = canonical;
}

Response StaticFiles::serve(const Request& request,
                            const std::vector<std::string>& segments) const {
  for (const auto& segment : segments)
    if (unsafe_segment(segment))
      return error_response(
          400, "unsafe_path",
          "path segment '" + segment + "' may not name a file outside the web folder");
  for (const auto& segment : segments)
    if (!segment.empty() && segment.front() == '.') return not_found("no such file");

  fs::path relative;
  for (const auto& segment : segments) relative /= segment;
  if (segments.empty()) relative = "index.html";

  std::error_code ec;
  const fs::path resolved = fs::canonical(root_ / relative, ec);
  if (ec) {
    if (segments.empty())
      return not_found("the web dashboard is not installed: no index.html in " + root_.string());
    return not_found("no such file: /" + relative.generic_string());
  }
  // A symlink inside the folder must not lead out of it.
  const auto [root_end, unused] = std::mismatch(root_.begin(), root_.end(), resolved.begin());
  (void)unused;
  if (root_end != root_.end() || !fs::is_regular_file(resolved, ec))
    return not_found("no such file: /" + relative.generic_string());

  const uint64_t size = fs::file_size(resolved, ec);
  if (ec) return not_found("no such file: /" + relative.generic_string());

  Response response;
  response.status = 200;
  const std::string extension = resolved.extension().string();
  response.headers.set("Content-Type",
                       mime_type_for_extension(extension.empty() ? "" : extension.substr(1)));
  const bool vendored = !segments.empty() && segments.front() == "vendor";
  response.headers.set("Cache-Control", vendored ? kImmutable : "no-cache");

  std::vector<std::string> hashes;
  const bool html = extension == ".html";
  if (html) {
    response.body = read_file(resolved);
    hashes = inline_script_hashes(response.body);
  } else {
    response.file = FileRegion{resolved, 0, size};
  }
  set_security_headers(response, content_security_policy(hashes));

  const std::string etag = file_etag(resolved, size);
  response.headers.set("ETag", etag);
  if (auto none_match = request.headers.get("If-None-Match");
      none_match && etag_listed(*none_match, etag)) {
    response.status = 304;
    response.body.clear();
    response.file.reset();
  }
  return response;
}

}  // namespace keel::server
