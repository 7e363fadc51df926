#include "worker/io/text_lines.h"

#include <charconv>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>

#include "worker/io/display_path.h"
#include "worker/io/io_error.h"

namespace keel::io {

std::string read_file_bytes(const std::filesystem::path& path) {
  std::unique_ptr<FILE, int (*)(FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!file) throw IoError(display_path(path) + ": cannot open: " + std::strerror(errno));
  // One allocation and one read of the whole file (its size from the open file); a file that
  // grows meanwhile is read to its end in further chunks.
  std::string bytes;
  std::error_code ec;
  const uintmax_t size = std::filesystem::file_size(path, ec);
  if (!ec && size > 0) {
    bytes.resize(static_cast<size_t>(size));
    bytes.resize(std::fread(bytes.data(), 1, bytes.size(), file.get()));
  }
  char buffer[1 << 16];
  size_t n;
  while ((n = std::fread(buffer, 1, sizeof(buffer), file.get())) > 0) bytes.append(buffer, n);
  if (std::ferror(file.get())) throw IoError(display_path(path) + ": read error");
  return bytes;
}

TextLines::TextLines(const std::filesystem::path& path)
    : name_(display_path(path)), text_(read_file_bytes(path)) {}

bool TextLines::next(std::string_view& line) {
  if (position_ >= text_.size()) return false;
  const char* begin = text_.data() + position_;
  const void* newline = std::memchr(begin, '\n', text_.size() - position_);
  const size_t length =
      newline ? static_cast<const char*>(newline) - begin : text_.size() - position_;
  line = std::string_view(begin, length);
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  position_ += length + 1;
  ++line_number_;
  return true;
}

void TextLines::fail(const std::string& message) const {
  throw IoError(name_ + ":" + std::to_string(line_number_) + ": " + message);
}

void split_commas(std::string_view line, std::vector<std::string_view>& fields) {
  fields.clear();
  size_t start = 0;
  while (true) {
    const size_t comma = line.find(',', start);
    if (comma == std::string_view::npos) {
      fields.push_back(line.substr(start));
      return;
    }
    fields.push_back(line.substr(start, comma - start));
    start = comma + 1;
  }
}

std::string_view trim(std::string_view text) {
  while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) text.remove_prefix(1);
  while (!text.empty() && (text.back() == ' ' || text.back() == '\t' || text.back() == '\r'))
    text.remove_suffix(1);
  return text;
}

bool parse_double(std::string_view text, double& value) {
  text = trim(text);
  if (!text.empty() && text.front() == '+') text.remove_prefix(1);
  if (text.empty()) return false;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  return error == std::errc() && end == text.data() + text.size();
}

bool parse_int64(std::string_view text, int64_t& value) {
  text = trim(text);
  if (!text.empty() && text.front() == '+') text.remove_prefix(1);
  if (text.empty()) return false;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  return error == std::errc() && end == text.data() + text.size();
}

}  // namespace keel::io
