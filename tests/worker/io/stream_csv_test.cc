#include "worker/io/stream_csv.h"

#include <gtest/gtest.h>

#include <cmath>

#include "io_test_util.h"
#include "worker/io/loop_closures.h"

namespace keel::io {
namespace {

using testing::expect_error;
using testing::TempDir;
using testing::write_text;

TEST(StreamCsv, ImuRoundTripKeepsExactStampsAndValues) {
  TempDir dir;
  ImuSeries written;
  for (int i = 0; i < 1000; ++i) {
    ImuSample s;
    s.t_ns = 1700000000123456789LL + i * 5000000LL;  // 200 Hz, 9 fractional digits
    s.gyro_rad_s = {0.001 * i, -0.5 + 1e-7 * i, 1.0 / 3.0};
    s.accel_m_s2 = {0.1, 0.2 * std::sin(i), 9.80665};
    written.push_back(s);
  }
  write_imu_csv(dir / "imu.csv", written);
  const ImuSeries read = read_imu_csv(dir / "imu.csv");
  ASSERT_EQ(read.size(), written.size());
  for (size_t i = 0; i < read.size(); ++i) {
    EXPECT_EQ(read[i].t_ns, written[i].t_ns);
    EXPECT_EQ(read[i].gyro_rad_s, written[i].gyro_rad_s);  // shortest round-trip text: exact
    EXPECT_EQ(read[i].accel_m_s2, written[i].accel_m_s2);
  }
}

TEST(StreamCsv, HandWrittenImuParsesExactly) {
  TempDir dir;
  write_text(dir / "imu.csv",
             "t,wx,wy,wz,ax,ay,az\n12.000000001,1,2,3,4,5,6\r\n12.5,-1e-3,0,0,0,0,9.81\n");
  const ImuSeries read = read_imu_csv(dir / "imu.csv");
  ASSERT_EQ(read.size(), 2u);
  EXPECT_EQ(read[0].t_ns, 12000000001LL);
  EXPECT_EQ(read[1].t_ns, 12500000000LL);
  EXPECT_EQ(read[0].accel_m_s2.z(), 6.0);
  EXPECT_EQ(read[1].gyro_rad_s.x(), -1e-3);
}

TEST(StreamCsv, DvlValidColumnAndRoundTrip) {
  TempDir dir;
  write_text(dir / "dvl.csv",
             "t,vx,vy,vz,valid\n1.0,0.5,0,0,1\n1.05,nan,nan,nan,0\n1.1,0.4,0.1,0,1\n");
  const DvlSeries read = read_dvl_csv(dir / "dvl.csv");
  ASSERT_EQ(read.size(), 3u);
  EXPECT_TRUE(read[0].valid);
  EXPECT_FALSE(read[1].valid);
  EXPECT_EQ(read[2].velocity_m_s.y(), 0.1);
  write_dvl_csv(dir / "dvl2.csv", read);
  const DvlSeries again = read_dvl_csv(dir / "dvl2.csv");
  ASSERT_EQ(again.size(), 3u);
  EXPECT_FALSE(again[1].valid);
  EXPECT_EQ(again[2].t_ns, 1100000000LL);
}

TEST(StreamCsv, DvlRangesAllowNan) {
  TempDir dir;
  write_text(dir / "r.csv", "t,r0,r1,r2,r3\n0.0,1.5,nan,1.7,1.8\n0.1,1.4,1.5,NaN,1.9\n");
  const DvlRangesSeries read = read_dvl_ranges_csv(dir / "r.csv");
  ASSERT_EQ(read.size(), 2u);
  EXPECT_TRUE(std::isnan(read[0].range_m[1]));
  EXPECT_TRUE(std::isnan(read[1].range_m[2]));
  EXPECT_EQ(read[1].range_m[3], 1.9);
  write_dvl_ranges_csv(dir / "r2.csv", read);
  EXPECT_TRUE(std::isnan(read_dvl_ranges_csv(dir / "r2.csv")[0].range_m[1]));
}

TEST(StreamCsv, DepthAndServoRoundTrip) {
  TempDir dir;
  write_depth_csv(dir / "depth.csv", {{1000, 2.5}, {2000, 2.75}});
  write_servo_csv(dir / "servo.csv", {{1000, -0.25}, {3000, 0.125}});
  const auto depth = read_depth_csv(dir / "depth.csv");
  const auto servo = read_servo_csv(dir / "servo.csv");
  ASSERT_EQ(depth.size(), 2u);
  ASSERT_EQ(servo.size(), 2u);
  EXPECT_EQ(depth[1].t_ns, 2000);
  EXPECT_EQ(depth[1].depth_m, 2.75);
  EXPECT_EQ(servo[1].t_ns, 3000);
  EXPECT_EQ(servo[0].angle_rad, -0.25);
}

TEST(StreamCsv, NonMonotonicTimestampNamesFileAndLine) {
  TempDir dir;
  write_text(dir / "imu.csv",
             "t,wx,wy,wz,ax,ay,az\n1.0,0,0,0,0,0,0\n1.2,0,0,0,0,0,0\n1.1,0,0,0,0,0,0\n");
  expect_error([&] { read_imu_csv(dir / "imu.csv"); }, {"imu.csv:4:", "decreasing", "line 3"});
}

TEST(StreamCsv, DuplicateTimestampNamesFileAndLine) {
  TempDir dir;
  write_text(dir / "depth.csv", "t,depth\n5.0,1\n5.000000000,2\n");
  expect_error([&] { read_depth_csv(dir / "depth.csv"); }, {"depth.csv:3:", "duplicate timestamp"});
}

TEST(StreamCsv, NanWhereNotAllowedNamesColumnAndLine) {
  TempDir dir;
  write_text(dir / "imu.csv", "t,wx,wy,wz,ax,ay,az\n1.0,0,0,0,0,0,0\n1.1,0,0,0,nan,0,0\n");
  expect_error([&] { read_imu_csv(dir / "imu.csv"); },
               {"imu.csv:3:", "column 'ax'", "finite", "nan"});
  write_text(dir / "servo.csv", "t,angle\n1.0,inf\n");
  expect_error([&] { read_servo_csv(dir / "servo.csv"); }, {"servo.csv:2:", "column 'angle'"});
  write_text(dir / "r.csv", "t,r0,r1,r2,r3\n0.0,1.5,inf,1.7,1.8\n");
  expect_error([&] { read_dvl_ranges_csv(dir / "r.csv"); }, {"r.csv:2:", "column 'r1'"});
}

TEST(StreamCsv, WrongColumnCountNamesLine) {
  TempDir dir;
  write_text(dir / "dvl.csv", "t,vx,vy,vz\n1.0,0,0,0\n1.1,0,0\n");
  expect_error([&] { read_dvl_csv(dir / "dvl.csv"); },
               {"dvl.csv:3:", "expected 4 columns", "found 3"});
}

TEST(StreamCsv, WrongHeaderShowsExpectedAndFound) {
  TempDir dir;
  write_text(dir / "imu.csv", "t,ax,ay,az,wx,wy,wz\n1.0,0,0,0,0,0,0\n");
  expect_error([&] { read_imu_csv(dir / "imu.csv"); },
               {"imu.csv:1:", "expected 't,wx,wy,wz,ax,ay,az'", "found 't,ax,ay,az,wx,wy,wz'"});
  write_text(dir / "empty.csv", "");
  expect_error([&] { read_depth_csv(dir / "empty.csv"); }, {"empty.csv", "empty file"});
}

TEST(StreamCsv, BadTimeAndMissingFile) {
  TempDir dir;
  write_text(dir / "depth.csv", "t,depth\n1.0x,1\n");
  expect_error([&] { read_depth_csv(dir / "depth.csv"); }, {"depth.csv:2:", "column 't'", "1.0x"});
  expect_error([&] { read_depth_csv(dir / "absent.csv"); }, {"absent.csv", "cannot open"});
}

TEST(LoopClosures, RoundTripAndErrors) {
  TempDir dir;
  LoopClosure loop;
  loop.t_i_ns = 100000000000;
  loop.t_j_ns = 160000000001;
  loop.T_body_i_body_j =
      make_pose(Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ())),
                Eigen::Vector3d(1, 2, 3));
  loop.sigma_t_m = 0.05;
  loop.sigma_r_rad = 0.01;
  write_loop_closures(dir / "loops.csv", {loop});
  const auto read = read_loop_closures(dir / "loops.csv");
  ASSERT_EQ(read.size(), 1u);
  EXPECT_EQ(read[0].t_j_ns, loop.t_j_ns);
  EXPECT_TRUE(read[0].T_body_i_body_j.isApprox(loop.T_body_i_body_j, 1e-12));
  EXPECT_EQ(read[0].sigma_t_m, 0.05);
  write_text(dir / "bad.csv",
             "t_i,t_j,x,y,z,qx,qy,qz,qw,sigma_t,sigma_r\n1,2,0,0,0,0,0,0,2,0.1,0.1\n");
  expect_error([&] { read_loop_closures(dir / "bad.csv"); }, {"bad.csv:2:", "|q| = 2"});
}

}  // namespace
}  // namespace keel::io
