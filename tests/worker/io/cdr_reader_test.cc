// CDR against bytes laid out by hand from DDS-XTypes 1.3 §7.4 (alignment relative to the end
// of the encapsulation header; XCDR2 caps it at 4), and its bounds checks.
#include "worker/io/bag/cdr_reader.h"

#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "io_test_util.h"
#include "worker/io/bag/bag_format_error.h"
#include "worker/io/bag/ros2_messages.h"

namespace keel::io {
namespace {

std::vector<uint8_t> bytes(std::initializer_list<int> values) {
  std::vector<uint8_t> out;
  for (int v : values) out.push_back(static_cast<uint8_t>(v));
  return out;
}

void put_f64(std::vector<uint8_t>& b, size_t at, double v, bool big_endian = false) {
  uint8_t raw[8];
  std::memcpy(raw, &v, 8);
  for (int i = 0; i < 8; ++i) b[at + i] = raw[big_endian ? 7 - i : i];
}

TEST(CdrReader, AlignsEachValueToItsSizeAfterTheHeader) {
  // CDR_LE: u8 at 0, f64 at 8 (7 pad bytes), u32 at 16, string "ab" at 20.
  std::vector<uint8_t> b(4 + 27, 0);
  b[1] = 0x01;
  b[4 + 0] = 7;
  put_f64(b, 4 + 8, 2.5);
  b[4 + 16] = 0x2A;  // u32 42
  b[4 + 20] = 3;     // string length with the NUL
  b[4 + 24] = 'a', b[4 + 25] = 'b', b[4 + 26] = 0;
  CdrReader cdr(b.data(), b.size());
  EXPECT_EQ(cdr.u8("a"), 7);
  EXPECT_EQ(cdr.f64("b"), 2.5);
  EXPECT_EQ(cdr.u32("c"), 42u);
  EXPECT_EQ(cdr.string("d"), "ab");
  EXPECT_EQ(cdr.offset(), b.size());
}

TEST(CdrReader, Xcdr2CapsAlignmentAtFourAndBigEndianIsSwapped) {
  // PLAIN_CDR2_BE: u8 at 0, f64 at 4 (XCDR2 aligns 8-byte values to 4).
  std::vector<uint8_t> b(4 + 12, 0);
  b[1] = 0x06;
  b[4] = 1;
  put_f64(b, 4 + 4, -3.25, /*big_endian=*/true);
  CdrReader cdr(b.data(), b.size());
  EXPECT_EQ(cdr.u8("a"), 1);
  EXPECT_EQ(cdr.f64("b"), -3.25);
}

TEST(CdrReader, LengthsPastTheEndAreErrorsNamingTheField) {
  // A string claiming 4294967295 bytes in a 12-byte message.
  const auto huge = bytes({0, 1, 0, 0, 0xFF, 0xFF, 0xFF, 0xFF, 'x', 0, 0, 0});
  testing::expect_error(
      [&] {
        CdrReader cdr(huge.data(), huge.size());
        cdr.string("header.frame_id");
      },
      {"field 'header.frame_id'", "4294967295", "runs past the end of the 12-byte message"});
  // A sequence count whose elements cannot fit.
  const auto seq = bytes({0, 1, 0, 0, 0x00, 0x00, 0x01, 0x00});
  testing::expect_error(
      [&] {
        CdrReader cdr(seq.data(), seq.size());
        cdr.sequence("fields", 13);
      },
      {"field 'fields'", "65536 elements"});
  // A value cut off, an unknown encapsulation, a message shorter than its header.
  const auto cut = bytes({0, 1, 0, 0, 1, 2});
  testing::expect_error(
      [&] {
        CdrReader cdr(cut.data(), cut.size());
        cdr.u32("height");
      },
      {"field 'height'"});
  const auto pl = bytes({0, 3, 0, 0});
  testing::expect_error([&] { CdrReader cdr(pl.data(), pl.size()); }, {"encapsulation 0x0003"});
  testing::expect_error([&] { CdrReader cdr(pl.data(), 2); }, {"shorter than"});
}

TEST(Ros2Messages, ImuFieldsComeFromTheirOffsets) {
  // sensor_msgs/msg/Imu: header (sec, nanosec, frame "imu"), orientation, 9 covariances,
  // angular_velocity, 9, linear_acceleration, 9. frame_id ends at payload byte 12 + 4 = 16.
  std::vector<uint8_t> b(4 + 16 + 8 * (4 + 9 + 3 + 9 + 3 + 9), 0);
  b[1] = 0x01;
  b[4] = 5;         // sec = 5
  b[4 + 4] = 0x10;  // nanosec = 16
  b[4 + 8] = 4;     // "imu\0"
  std::memcpy(&b[4 + 12], "imu", 4);
  const size_t gyro = 4 + 16 + 8 * (4 + 9);
  const size_t accel = gyro + 8 * (3 + 9);
  for (int i = 0; i < 3; ++i) put_f64(b, gyro + 8 * i, 0.1 * (i + 1));
  for (int i = 0; i < 3; ++i) put_f64(b, accel + 8 * i, -9.81 * (i == 2));
  const ros2::Imu imu = ros2::decode_imu(b.data(), b.size());
  EXPECT_EQ(imu.stamp_ns, 5000000016);
  EXPECT_EQ(imu.angular_velocity, Eigen::Vector3d(0.1, 0.2, 0.30000000000000004));
  EXPECT_EQ(imu.linear_acceleration.z(), -9.81);
  // One byte short: the last covariance runs past the end.
  testing::expect_error([&] { ros2::decode_imu(b.data(), b.size() - 1); },
                        {"linear_acceleration_covariance"});
}

}  // namespace
}  // namespace keel::io
