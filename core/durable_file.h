// POSIX file I/O for crash safety: an owned descriptor with full writes, fsync and truncate,
// and fsync of a directory (needed after a rename or create for the entry to be durable).
// Errors are std::system_error whose what() names the file and the failed call.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>

namespace keel {

class DurableFile {
 public:
  enum class Mode {
    kCreateNew,     // O_CREAT | O_EXCL: fails if the file exists (temp files)
    kOpenOrCreate,  // O_CREAT: keeps existing bytes (upload part files)
  };
  DurableFile(const std::filesystem::path& path, Mode mode);
  ~DurableFile();
  DurableFile(const DurableFile&) = delete;
  DurableFile& operator=(const DurableFile&) = delete;

  // Writes all `size` bytes at `offset` (retrying short writes and EINTR).
  void write_at(int64_t offset, const void* data, size_t size);
  void truncate(int64_t size);
  void sync();  // fsync: the bytes are on disk when this returns
  int64_t size() const;
  const std::filesystem::path& path() const { return path_; }

 private:
  [[noreturn]] void fail(const char* call) const;

  std::filesystem::path path_;
  int fd_ = -1;
};

// fsync on the directory itself, so a rename or new entry in it survives a power loss.
void fsync_directory(const std::filesystem::path& directory);

}  // namespace keel
