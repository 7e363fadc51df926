// Writes one ROS 2 message as plain little-endian CDR (XCDR1, encapsulation 0x0001): what
// every ROS 2 RMW publishes and rosbag2 stores. Each value is aligned to its size relative to
// the end of the 4-byte encapsulation header (DDS-XTypes 1.3 §7.4.1).
#pragma once

#include <cstdint>
#include <cstring>
#include <string_view>
#include <vector>

namespace keel::sim {

class CdrWriter {
 public:
  CdrWriter() : bytes_{0x00, 0x01, 0x00, 0x00} {}

  void u8(uint8_t v) { put(v); }
  void u16(uint16_t v) { put(v); }
  void boolean(bool v) { put(static_cast<uint8_t>(v ? 1 : 0)); }
  void u32(uint32_t v) { put(v); }
  void i32(int32_t v) { put(v); }
  void i64(int64_t v) { put(v); }
  void f32(float v) { put(v); }
  void f64(double v) { put(v); }
  // uint32 length counting the terminating NUL, the bytes, the NUL.
  void string(std::string_view s) {
    u32(static_cast<uint32_t>(s.size() + 1));
    bytes_.insert(bytes_.end(), s.begin(), s.end());
    bytes_.push_back(0);
  }
  // uint8[]: uint32 count, the bytes.
  void byte_sequence(const uint8_t* data, size_t size) {
    u32(static_cast<uint32_t>(size));
    bytes_.insert(bytes_.end(), data, data + size);
  }
  void sequence(uint32_t count) { u32(count); }

  const std::vector<uint8_t>& bytes() const { return bytes_; }
  std::vector<uint8_t> take() { return std::move(bytes_); }

 private:
  template <typename T>
  void put(T v) {
    while ((bytes_.size() - 4) % sizeof(T) != 0) bytes_.push_back(0);
    const size_t at = bytes_.size();
    bytes_.resize(at + sizeof(T));
    std::memcpy(bytes_.data() + at, &v, sizeof(T));
  }

  std::vector<uint8_t> bytes_;
};

}  // namespace keel::sim
