// Random-access bytes of a container file (MCAP): a file read with pread, or a buffer in
// memory (the fuzzers). Reads past the end throw; callers check lengths first and name
// the record that claims them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace keel::io {

class ByteSource {
 public:
  virtual ~ByteSource() = default;
  virtual uint64_t size() const = 0;
  // Copies [offset, offset + n) into `out`; throws BagFormatError past the end and IoError on
  // a read error.
  virtual void read(uint64_t offset, size_t n, uint8_t* out) const = 0;
};

class FileBytes : public ByteSource {
 public:
  // `name` is the file as errors show it (display_path). Throws IoError naming it.
  FileBytes(const std::filesystem::path& path, std::string name);
  ~FileBytes() override;
  FileBytes(const FileBytes&) = delete;
  FileBytes& operator=(const FileBytes&) = delete;
  uint64_t size() const override { return size_; }
  void read(uint64_t offset, size_t n, uint8_t* out) const override;

 private:
  std::string name_;
  int fd_ = -1;
  uint64_t size_ = 0;
};

class MemoryBytes : public ByteSource {
 public:
  MemoryBytes(const uint8_t* data, size_t size) : data_(data), size_(size) {}
  uint64_t size() const override { return size_; }
  void read(uint64_t offset, size_t n, uint8_t* out) const override;

 private:
  const uint8_t* data_;
  size_t size_;
};

}  // namespace keel::io
