#include "worker/main/blob_cache.h"

#include <signal.h>
#include <unistd.h>

#include <spdlog/spdlog.h>
#include <cerrno>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "proto/resources.h"

namespace keel::worker {

namespace fs = std::filesystem;

namespace {

constexpr const char* kPartialMarker = ".dl-";

bool process_alive(long pid) { return pid > 0 && (::kill(pid, 0) == 0 || errno == EPERM); }

}  // namespace

BlobCache::BlobCache(fs::path folder) : folder_(std::move(folder)) {
  fs::create_directories(folder_);
  // "<sha>.dl-<pid>[.part]": a download of worker <pid>; stale once that process is gone.
  std::error_code ec;
  for (const auto& item : fs::directory_iterator(folder_, ec)) {
    const std::string name = item.path().filename().string();
    const size_t marker = name.find(kPartialMarker);
    if (marker == std::string::npos) continue;
    const long pid =
        std::atol(name.c_str() + marker + std::char_traits<char>::length(kPartialMarker));
    if (!process_alive(pid)) fs::remove(item.path(), ec);
  }
}

fs::path BlobCache::fetch(client::ApiClient& api, const std::string& sha256) {
  if (!proto::is_sha256_hex(sha256))
    throw std::invalid_argument("blob id '" + sha256 + "' is not a SHA-256 hex digest");
  const fs::path cached = folder_ / sha256;
  std::error_code ec;
  if (fs::is_regular_file(cached, ec)) {
    spdlog::debug("blob {} found in the cache", sha256);
    return cached;
  }
  const fs::path partial = folder_ / (sha256 + kPartialMarker + std::to_string(::getpid()));
  spdlog::info("downloading blob {}", sha256);
  api.download("/v1/blobs/" + sha256, partial, sha256);
  fs::rename(partial, cached);  // atomic; another worker's identical copy may be replaced
  return cached;
}

}  // namespace keel::worker
