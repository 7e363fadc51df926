#include "core/durable_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <string>
#include <system_error>

namespace keel {

namespace {

[[noreturn]] void throw_errno(const std::filesystem::path& path, const char* call) {
  throw std::system_error(errno, std::generic_category(), path.string() + ": " + call);
}

}  // namespace

DurableFile::DurableFile(const std::filesystem::path& path, Mode mode) : path_(path) {
  const int flags = O_RDWR | O_CLOEXEC | O_CREAT | (mode == Mode::kCreateNew ? O_EXCL : 0);
  do {
    fd_ = ::open(path.c_str(), flags, 0644);
  } while (fd_ < 0 && errno == EINTR);
  if (fd_ < 0) fail("open");
}

DurableFile::~DurableFile() {
  if (fd_ >= 0) ::close(fd_);
}

void DurableFile::fail(const char* call) const { throw_errno(path_, call); }

void DurableFile::write_at(int64_t offset, const void* data, size_t size) {
  const char* bytes = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t written = ::pwrite(fd_, bytes, size, static_cast<off_t>(offset));
    if (written < 0) {
      if (errno == EINTR) continue;
      fail("pwrite");
    }
    bytes += written;
    offset += written;
    size -= static_cast<size_t>(written);
  }
}

void DurableFile::truncate(int64_t size) {
  if (::ftruncate(fd_, static_cast<off_t>(size)) != 0) fail("ftruncate");
}

void DurableFile::sync() {
  if (::fsync(fd_) != 0) fail("fsync");
}

int64_t DurableFile::size() const {
  struct stat info {};
  if (::fstat(fd_, &info) != 0) fail("fstat");
  return static_cast<int64_t>(info.st_size);
}

void fsync_directory(const std::filesystem::path& directory) {
  const int fd = ::open(directory.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) throw_errno(directory, "open directory");
  const int result = ::fsync(fd);
  const int saved = errno;
  ::close(fd);
  errno = saved;
  if (result != 0) throw_errno(directory, "fsync directory");
}

}  // namespace keel
