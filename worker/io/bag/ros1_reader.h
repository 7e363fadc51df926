// Reads one ROS1-serialised message (wiki.ros.org/msg, "Message serialization"): the fields in
// order, little endian, packed without alignment; strings and variable-length arrays as a
// uint32 count then their elements (strings carry no NUL); fixed-length arrays as their
// elements alone. The same accessors as CdrReader (cdr_reader.h), so decoders read alike.
// Every read is bounds-checked; a length or count that runs past the end throws
// BagFormatError naming the field, e.g. "ROS1: field 'data' needs 4294967295 bytes at offset
// 60; the 97-byte message has 33 left".
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string_view>

namespace keel::io {

class Ros1Reader {
 public:
  Ros1Reader(const uint8_t* data, size_t size) : data_(data), size_(size) {}

  uint8_t u8(const char* field) { return read<uint8_t>(field); }
  uint16_t u16(const char* field) { return read<uint16_t>(field); }
  bool boolean(const char* field) { return read<uint8_t>(field) != 0; }
  uint32_t u32(const char* field) { return read<uint32_t>(field); }
  int32_t i32(const char* field) { return read<int32_t>(field); }
  uint64_t u64(const char* field) { return read<uint64_t>(field); }
  int64_t i64(const char* field) { return read<int64_t>(field); }
  double f64(const char* field) { return read<double>(field); }
  // string: uint32 length, then the bytes.
  std::string_view string(const char* field) { return bytes(field); }
  // A variable-length array's element count, checked against the bytes left for
  // `min_element_bytes` each.
  uint32_t sequence(const char* field, size_t min_element_bytes) {
    const uint32_t count = u32(field);
    need(uint64_t(count) * min_element_bytes, field);
    return count;
  }
  // uint8[] (or a string): a view into the message.
  std::string_view bytes(const char* field) {
    const uint32_t count = sequence(field, 1);
    const char* begin = reinterpret_cast<const char*>(data_ + at_);
    at_ += count;
    return {begin, count};
  }
  // A fixed-length float64[count] that is not needed (covariance arrays).
  void skip_f64(const char* field, size_t count) {
    need(uint64_t(count) * 8, field);
    at_ += count * 8;
  }

  template <typename T>
  T read(const char* field) {
    need(sizeof(T), field);
    T value;
    std::memcpy(&value, data_ + at_, sizeof(T));  // little-endian host (x86-64, arm64)
    at_ += sizeof(T);
    return value;
  }

  size_t offset() const { return at_; }
  size_t size() const { return size_; }

 private:
  void need(uint64_t bytes, const char* field) const {
    if (bytes > size_ - at_) overrun(bytes, field);
  }
  [[noreturn]] void overrun(uint64_t bytes, const char* field) const;

  const uint8_t* data_;
  size_t size_;
  size_t at_ = 0;
};

}  // namespace keel::io
