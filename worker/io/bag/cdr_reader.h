// Reads one CDR-serialised ROS 2 message (OMG DDS-XTypes 1.3 §7.4, the RTPS serialized
// payload ROS 2 bags store): a 4-byte encapsulation header, then the fields in order, each
// aligned to its size relative to the end of the header. Plain CDR (XCDR1, what every ROS 2
// RMW writes) and plain XCDR2 (alignment capped at 4), little or big endian.
// Every read is bounds-checked; a length or count that runs past the end throws
// BagFormatError naming the field, e.g. "field 'data': sequence of 4294967295 x 1 bytes at
// offset 60 runs past the end of the 128-byte message".
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>

namespace keel::io {

class CdrReader {
 public:
  CdrReader(const uint8_t* data, size_t size);

  uint8_t u8(const char* field) { return read<uint8_t>(field); }
  uint16_t u16(const char* field) { return read<uint16_t>(field); }
  bool boolean(const char* field) { return read<uint8_t>(field) != 0; }
  uint32_t u32(const char* field) { return read<uint32_t>(field); }
  int32_t i32(const char* field) { return read<int32_t>(field); }
  uint64_t u64(const char* field) { return read<uint64_t>(field); }
  float f32(const char* field) { return read<float>(field); }
  double f64(const char* field) { return read<double>(field); }
  // string: uint32 length including the terminating NUL, the bytes, the NUL (not returned).
  std::string_view string(const char* field);
  // A sequence's element count, checked against the bytes left for `min_element_bytes` each.
  uint32_t sequence(const char* field, size_t min_element_bytes);
  // uint8[] (a sequence of bytes): a view into the message.
  std::string_view bytes(const char* field);
  // `count` doubles that are not needed (covariance arrays).
  void skip_f64(const char* field, size_t count);

  size_t offset() const { return position_; }
  size_t size() const { return size_; }

 private:
  template <typename T>
  T read(const char* field);
  void align(size_t size, const char* field);
  void need(size_t bytes, const char* field, const char* what) const;

  const uint8_t* data_;
  size_t size_;
  size_t position_ = 4;   // after the encapsulation header
  bool swap_ = false;     // big-endian data on this little-endian host
  size_t max_align_ = 8;  // 4 in XCDR2
};

}  // namespace keel::io
