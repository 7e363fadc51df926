#include "worker/io/text_writer.h"

#include <charconv>
#include <cmath>
#include <cstring>

#include "worker/io/io_error.h"

namespace keel::io {

TextWriter::TextWriter(const std::filesystem::path& path) : path_(path.string()) {
  file_ = std::fopen(path_.c_str(), "wb");
  if (!file_) throw IoError(path_ + ": cannot create: " + std::strerror(errno));
  buffer_.reserve(1 << 16);
}

TextWriter::~TextWriter() {
  if (file_) std::fclose(file_);
}

TextWriter& TextWriter::text(std::string_view s) {
  buffer_.append(s);
  if (buffer_.size() > (1 << 16)) {
    if (std::fwrite(buffer_.data(), 1, buffer_.size(), file_) != buffer_.size())
      throw IoError(path_ + ": write failed: " + std::strerror(errno));
    buffer_.clear();
  }
  return *this;
}

TextWriter& TextWriter::number(double value) {
  if (std::isnan(value)) return text("nan");
  char digits[32];
  const auto result = std::to_chars(digits, digits + sizeof(digits), value);
  return text(std::string_view(digits, result.ptr - digits));
}

TextWriter& TextWriter::seconds(TimeNs t_ns) { return text(format_seconds(t_ns)); }

TextWriter& TextWriter::integer(long long value) { return text(std::to_string(value)); }

void TextWriter::close() {
  if (!file_) return;
  const bool ok = std::fwrite(buffer_.data(), 1, buffer_.size(), file_) == buffer_.size();
  const bool closed = std::fclose(file_) == 0;
  file_ = nullptr;
  if (!ok || !closed) throw IoError(path_ + ": write failed");
}

}  // namespace keel::io
