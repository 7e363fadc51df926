#include "storage/blob_store.h"

#include <stdexcept>
#include <system_error>

#include "proto/resources.h"
#include "core/durable_file.h"
#include "storage/ids.h"
#include "core/sha256.h"

namespace keel::storage {

namespace fs = std::filesystem;

BlobStore::BlobStore(fs::path blobs_dir, fs::path tmp_dir)
    : blobs_dir_(std::move(blobs_dir)), tmp_dir_(std::move(tmp_dir)) {
  fs::create_directories(blobs_dir_);
  fs::create_directories(tmp_dir_);
}

fs::path BlobStore::path_of(const std::string& sha256) const {
  if (!proto::is_sha256_hex(sha256))
    throw std::invalid_argument("blob id '" + sha256 + "': expected 64 lowercase hex digits");
  return blobs_dir_ / sha256.substr(0, 2) / sha256;
}

bool BlobStore::contains(const std::string& sha256) const {
  std::error_code error;
  return fs::is_regular_file(path_of(sha256), error);
}

int64_t BlobStore::size_of(const std::string& sha256) const {
  return static_cast<int64_t>(fs::file_size(path_of(sha256)));
}

fs::path BlobStore::temp_path() const { return tmp_dir_ / (random_hex(12) + ".tmp"); }

std::string BlobStore::put(const std::string& bytes) {
  const std::string sha256 = sha256_bytes(bytes);
  if (contains(sha256)) return sha256;
  const fs::path temp = temp_path();
  try {
    DurableFile file(temp, DurableFile::Mode::kCreateNew);
    file.write_at(0, bytes.data(), bytes.size());
    file.sync();
  } catch (...) {
    std::error_code ignored;
    fs::remove(temp, ignored);
    throw;
  }
  move_into_place(temp, sha256);
  return sha256;
}

void BlobStore::adopt(const fs::path& file, const std::string& sha256) {
  if (contains(sha256)) {
    fs::remove(file);
    return;
  }
  move_into_place(file, sha256);
}

void BlobStore::move_into_place(const fs::path& file, const std::string& sha256) {
  const fs::path target = path_of(sha256);
  const fs::path folder = target.parent_path();
  if (!fs::is_directory(folder)) {
    fs::create_directories(folder);
    fsync_directory(blobs_dir_);
  }
  // Concurrent writers of the same content each rename their own complete copy: the last
  // rename wins and every reader sees complete bytes either way.
  fs::rename(file, target);
  fsync_directory(folder);
}

void BlobStore::clear_tmp() {
  for (const auto& entry : fs::directory_iterator(tmp_dir_)) fs::remove_all(entry.path());
}

}  // namespace keel::storage
