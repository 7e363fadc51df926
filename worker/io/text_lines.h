// A text file read whole into memory and walked line by line, with 1-based line numbers for
// error messages. Streams of an hour (720k IMU rows, ~50 MB) fit comfortably; no iostream per
// line.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "core/time.h"

namespace keel::io {

// Reads a whole file; throws IoError naming the path when it cannot be read.
std::string read_file_bytes(const std::filesystem::path& path);

class TextLines {
 public:
  explicit TextLines(const std::filesystem::path& path);
  // Next line without its '\n' (and '\r'); false at the end.
  bool next(std::string_view& line);
  size_t line_number() const { return line_number_; }
  const std::string& name() const { return name_; }
  // "<file>:<line>: <message>"
  [[noreturn]] void fail(const std::string& message) const;

 private:
  std::string name_;
  std::string text_;
  size_t position_ = 0;
  size_t line_number_ = 0;
};

// Splits on ',' (stream CSVs have no quoting); fields keep surrounding spaces.
void split_commas(std::string_view line, std::vector<std::string_view>& fields);
std::string_view trim(std::string_view text);
// std::from_chars on a trimmed field; accepts nan/inf spellings. False when not a number.
bool parse_double(std::string_view text, double& value);
bool parse_int64(std::string_view text, int64_t& value);

}  // namespace keel::io
