// Blobs (mission bundles, CAD meshes) fetched from the server, cached on disk by SHA-256 so
// a mission processed again (reprocessing, retries) is not downloaded again.
// Several workers may share one cache folder: each downloads to its own temporary name and
// renames it into place, and the same SHA-256 always means the same bytes.
#pragma once

#include <filesystem>
#include <string>

#include "client/api_client.h"

namespace keel::worker {

class BlobCache {
 public:
  // Creates `folder` and removes partial downloads left by workers that are gone.
  explicit BlobCache(std::filesystem::path folder);

  // The cached file of blob `sha256`, downloaded through GET /v1/blobs/{sha256} (checked
  // against the hash) when absent. Throws std::invalid_argument for a malformed hash.
  std::filesystem::path fetch(client::ApiClient& api, const std::string& sha256);

  const std::filesystem::path& folder() const { return folder_; }

 private:
  std::filesystem::path folder_;
};

}  // namespace keel::worker
