// A whole file mapped read-only into memory (mmap with MAP_POPULATE: the pages come from the
// page cache in one call instead of a fault each, and nothing is copied), for the point file
// readers, whose bodies are used in place.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string_view>

namespace keel::io {

class MappedFile {
 public:
  // Throws IoError naming the file when it cannot be opened or mapped.
  explicit MappedFile(const std::filesystem::path& path);
  ~MappedFile();
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;

  std::string_view bytes() const { return {static_cast<const char*>(data_), size_}; }

 private:
  void* data_ = nullptr;
  size_t size_ = 0;
};

}  // namespace keel::io
