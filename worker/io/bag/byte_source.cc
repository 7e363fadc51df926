#include "worker/io/bag/byte_source.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "worker/io/bag/bag_format_error.h"
#include "worker/io/io_error.h"

namespace keel::io {

namespace {

void check_range(uint64_t offset, size_t n, uint64_t size) {
  if (offset > size || n > size - offset)
    throw BagFormatError("read of " + std::to_string(n) + " bytes at byte " +
                         std::to_string(offset) + " runs past the end of the " +
                         std::to_string(size) + "-byte file");
}

}  // namespace

FileBytes::FileBytes(const std::filesystem::path& path, std::string name) : name_(std::move(name)) {
  fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) throw IoError(name_ + ": cannot open: " + std::strerror(errno));
  struct stat st;
  if (::fstat(fd_, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd_);
    throw IoError(name_ + ": not a regular file");
  }
  size_ = static_cast<uint64_t>(st.st_size);
}

FileBytes::~FileBytes() {
  if (fd_ >= 0) ::close(fd_);
}

void FileBytes::read(uint64_t offset, size_t n, uint8_t* out) const {
  check_range(offset, n, size_);
  while (n > 0) {
    const ssize_t got = ::pread(fd_, out, n, static_cast<off_t>(offset));
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0)
      throw IoError(name_ + ": read error at byte " + std::to_string(offset) + ": " +
                    (got < 0 ? std::strerror(errno) : "unexpected end of file"));
    out += got;
    offset += static_cast<uint64_t>(got);
    n -= static_cast<size_t>(got);
  }
}

void MemoryBytes::read(uint64_t offset, size_t n, uint8_t* out) const {
  check_range(offset, n, size_);
  if (n > 0) std::memcpy(out, data_ + offset, n);
}

}  // namespace keel::io
