// A file written through a temporary sibling (`<path>.partial`) that commit() renames into
// place, so a failed or abandoned write never leaves a half-written file under the real name
// (and an earlier file of that name stays whole until the new one is complete).
#pragma once

#include <cstddef>
#include <filesystem>
#include <fstream>
#include <string>

namespace keel {

class ReplacedFile {
 public:
  // Throws std::runtime_error naming `path` and the reason when the temporary cannot be made.
  explicit ReplacedFile(std::filesystem::path path);
  ~ReplacedFile();  // without commit(): removes the temporary
  ReplacedFile(const ReplacedFile&) = delete;
  ReplacedFile& operator=(const ReplacedFile&) = delete;

  // Throws std::runtime_error naming the file when the bytes cannot be written (disk full).
  void append(const char* bytes, size_t size);
  // Flushes, closes and renames into place; throws naming the file on failure.
  void commit();

 private:
  std::filesystem::path path_, temporary_;
  std::ofstream out_;
  bool committed_ = false;
};

// `bytes` as the whole content of `path`, through a ReplacedFile.
void write_file_replacing(const std::filesystem::path& path, const std::string& bytes);

}  // namespace keel
