#include "worker/io/bag/cdr_reader.h"

#include <cstring>
#include <string>

#include "worker/io/bag/bag_format_error.h"

namespace keel::io {

namespace {

template <typename T>
T byte_swapped(T value) {
  uint8_t b[sizeof(T)];
  std::memcpy(b, &value, sizeof(T));
  for (size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
  std::memcpy(&value, b, sizeof(T));
  return value;
}

std::string hex2(uint8_t a, uint8_t b) {
  static const char* digits = "0123456789abcdef";
  return {'0', 'x', digits[a >> 4], digits[a & 15], digits[b >> 4], digits[b & 15]};
}

}  // namespace

CdrReader::CdrReader(const uint8_t* data, size_t size) : data_(data), size_(size) {
  if (size < 4)
    throw BagFormatError("CDR: " + std::to_string(size) +
                         "-byte message is shorter than its 4-byte encapsulation header");
  // Encapsulation identifier, big endian (RTPS 2.5 §10.2): 0x0000 CDR_BE, 0x0001 CDR_LE,
  // 0x0006 PLAIN_CDR2_BE, 0x0007 PLAIN_CDR2_LE.
  const uint16_t kind = static_cast<uint16_t>(data[0] << 8 | data[1]);
  switch (kind) {
    case 0x0000:
    case 0x0001:
      max_align_ = 8;
      break;
    case 0x0006:
    case 0x0007:
      max_align_ = 4;
      break;
    default:
      throw BagFormatError("CDR: encapsulation " + hex2(data[0], data[1]) +
                           " is not plain CDR (0x0000/0x0001) or plain XCDR2 (0x0006/0x0007)");
  }
  swap_ = (kind & 1) == 0;
}

void CdrReader::need(size_t bytes, const char* field, const char* what) const {
  if (bytes > size_ - position_)
    throw BagFormatError("CDR: field '" + std::string(field) + "': " + what + " of " +
                         std::to_string(bytes) + " bytes at offset " + std::to_string(position_) +
                         " runs past the end of the " + std::to_string(size_) + "-byte message");
}

void CdrReader::align(size_t size, const char* field) {
  const size_t a = size < max_align_ ? size : max_align_;
  const size_t origin_offset = position_ - 4;
  const size_t pad = (a - origin_offset % a) % a;
  need(pad, field, "alignment padding");
  position_ += pad;
}

template <typename T>
T CdrReader::read(const char* field) {
  align(sizeof(T), field);
  need(sizeof(T), field, "value");
  T value;
  std::memcpy(&value, data_ + position_, sizeof(T));
  position_ += sizeof(T);
  return swap_ ? byte_swapped(value) : value;
}

// The value types the header's accessors read.
template uint8_t CdrReader::read<uint8_t>(const char*);
template uint16_t CdrReader::read<uint16_t>(const char*);
template uint32_t CdrReader::read<uint32_t>(const char*);
template int32_t CdrReader::read<int32_t>(const char*);
template uint64_t CdrReader::read<uint64_t>(const char*);
template float CdrReader::read<float>(const char*);
template double CdrReader::read<double>(const char*);

std::string_view CdrReader::string(const char* field) {
  const uint32_t length = u32(field);
  need(length, field, "string");
  const char* text = reinterpret_cast<const char*>(data_ + position_);
  position_ += length;
  // The length counts the NUL; a writer that left it out is tolerated, not a NUL inside.
  size_t n = length;
  if (n > 0 && text[n - 1] == '\0') --n;
  return {text, n};
}

uint32_t CdrReader::sequence(const char* field, size_t min_element_bytes) {
  const uint32_t count = u32(field);
  if (min_element_bytes > 0 && static_cast<uint64_t>(count) * min_element_bytes > size_ - position_)
    throw BagFormatError("CDR: field '" + std::string(field) + "': sequence of " +
                         std::to_string(count) + " elements of at least " +
                         std::to_string(min_element_bytes) + " bytes at offset " +
                         std::to_string(position_) + " runs past the end of the " +
                         std::to_string(size_) + "-byte message");
  return count;
}

std::string_view CdrReader::bytes(const char* field) {
  const uint32_t count = sequence(field, 1);
  const char* begin = reinterpret_cast<const char*>(data_ + position_);
  position_ += count;
  return {begin, count};
}

void CdrReader::skip_f64(const char* field, size_t count) {
  if (count == 0) return;
  align(8, field);
  need(count * 8, field, "array");
  position_ += count * 8;
}

}  // namespace keel::io
