// The web dashboard's files (web/, installed next to the binaries) as HTTP answers: a pure
// function of a request path, no sockets. Chooses the MIME type by extension, refuses any
// path that could leave the folder (`..`, `.`, an encoded '/', '\', NUL, a symlink out),
// hides dot files, and sets the cache and security headers:
//   - `vendor/` holds third-party files under versioned folder names (three@0.187.0/...):
//     `Cache-Control: public, max-age=31536000, immutable`;
//   - everything else (index.html, the app's own modules) is `no-cache` with an ETag, so a
//     rebuilt page is seen at once and an unchanged one costs a 304.
// Every answer carries a Content-Security-Policy that allows only this origin, plus what
// the Draco decoder needs (`worker-src blob:`, `'wasm-unsafe-eval'`) and the SHA-256 of each
// inline <script> of index.html (its import map), computed from the file served.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "server/http_types.h"

namespace keel::server {

// "text/javascript; charset=utf-8" for "js", ... ; "application/octet-stream" when unknown.
std::string mime_type_for_extension(std::string_view extension);

// 'sha256-<base64>' sources for every inline <script> element of an HTML page (those
// without a src attribute), in order.
std::vector<std::string> inline_script_hashes(std::string_view html);

// The Content-Security-Policy for a page whose inline scripts have these hash sources.
std::string content_security_policy(const std::vector<std::string>& script_hashes);

class StaticFiles {
 public:
  // `root` need not exist: every request then answers 404 naming the folder.
  explicit StaticFiles(std::filesystem::path root);

  // GET (or HEAD) of the path segments below the root; {} = "/" = index.html.
  // 400 `unsafe_path` for a segment that could climb out, 404 for anything absent or hidden.
  Response serve(const Request& request, const std::vector<std::string>& segments) const;

  const std::filesystem::path& root() const { return root_; }

 private:
  std::filesystem::path root_;
};

}  // namespace keel::server
