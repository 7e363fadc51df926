#include "core/replaced_file.h"

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <system_error>
#include <utility>

namespace keel {

ReplacedFile::ReplacedFile(std::filesystem::path path)
    : path_(std::move(path)), temporary_(path_.string() + ".partial") {
  out_.open(temporary_, std::ios::binary | std::ios::trunc);
  if (!out_)
    throw std::runtime_error(path_.string() + ": cannot open for writing (" + std::strerror(errno) +
                             ")");
}

ReplacedFile::~ReplacedFile() {
  if (committed_) return;
  out_.close();
  std::error_code ignored;
  std::filesystem::remove(temporary_, ignored);
}

void ReplacedFile::append(const char* bytes, size_t size) {
  out_.write(bytes, static_cast<std::streamsize>(size));
  if (!out_) throw std::runtime_error(path_.string() + ": write failed (disk full?)");
}

void ReplacedFile::commit() {
  out_.close();
  if (!out_) throw std::runtime_error(path_.string() + ": write failed (disk full?)");
  std::error_code error;
  std::filesystem::rename(temporary_, path_, error);
  if (error) {
    throw std::runtime_error(path_.string() +
                             ": cannot move the written file into place: " + error.message());
  }
  committed_ = true;
}

void write_file_replacing(const std::filesystem::path& path, const std::string& bytes) {
  ReplacedFile file(path);
  file.append(bytes.data(), bytes.size());
  file.commit();
}

}  // namespace keel
