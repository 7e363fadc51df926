#include "storage/upload_area.h"

#include <system_error>

#include "core/durable_file.h"

namespace keel::storage {

namespace fs = std::filesystem;

namespace {
constexpr const char* kPartSuffix = ".part";
}  // namespace

UploadArea::UploadArea(fs::path dir) : dir_(std::move(dir)) { fs::create_directories(dir_); }

fs::path UploadArea::part_path(const std::string& upload_id) const {
  return dir_ / (upload_id + kPartSuffix);
}

void UploadArea::create(const std::string& upload_id) {
  DurableFile file(part_path(upload_id), DurableFile::Mode::kOpenOrCreate);
  file.truncate(0);
  file.sync();
  fsync_directory(dir_);
}

void UploadArea::write_chunk(const std::string& upload_id, int64_t committed, const char* data,
                             size_t size) {
  DurableFile file(part_path(upload_id), DurableFile::Mode::kOpenOrCreate);
  // Bytes past the committed offset are leftovers of a chunk that never committed.
  if (file.size() != committed) file.truncate(committed);
  try {
    file.write_at(committed, data, size);
    file.sync();
  } catch (...) {
    // A full disk (ENOSPC) cut the chunk: give back the space its bytes took. The offset was
    // not committed, so the next append or a restart would cut them anyway.
    try {
      file.truncate(committed);
    } catch (...) {
    }
    throw;
  }
}

int64_t UploadArea::truncate_to(const std::string& upload_id, int64_t committed) {
  DurableFile file(part_path(upload_id), DurableFile::Mode::kOpenOrCreate);
  const int64_t size = file.size();
  if (size > committed) {
    file.truncate(committed);
    file.sync();
    return committed;
  }
  return size;
}

void UploadArea::remove(const std::string& upload_id) {
  std::error_code ignored;
  fs::remove(part_path(upload_id), ignored);
}

std::vector<std::string> UploadArea::part_ids() const {
  std::vector<std::string> ids;
  for (const auto& entry : fs::directory_iterator(dir_)) {
    const fs::path& path = entry.path();
    if (entry.is_regular_file() && path.extension() == kPartSuffix)
      ids.push_back(path.stem().string());
  }
  return ids;
}

}  // namespace keel::storage
