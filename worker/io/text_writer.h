// A buffered text file writer with exact number formatting (shortest round-trip doubles,
// 9-digit seconds). Fails naming the file.
#pragma once

#include <cstdio>
#include <filesystem>
#include <string>
#include <string_view>

#include "core/time.h"

namespace keel::io {

class TextWriter {
 public:
  explicit TextWriter(const std::filesystem::path& path);
  ~TextWriter();
  TextWriter(const TextWriter&) = delete;
  TextWriter& operator=(const TextWriter&) = delete;

  TextWriter& text(std::string_view s);
  TextWriter& number(double value);  // shortest text that reads back to the same double
  TextWriter& seconds(TimeNs t_ns);  // "1700000000.123456789"
  TextWriter& integer(long long value);
  void close();  // flushes; throws IoError naming the file on failure

 private:
  std::string path_;
  std::FILE* file_ = nullptr;
  std::string buffer_;
};

}  // namespace keel::io
