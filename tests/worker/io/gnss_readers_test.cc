// GNSS fixes from a CSV stream, a ROS1 bag (written by Debian's python3-rosbag) and a ROS 2
// MCAP (written with keel-sim's CDR and MCAP writers), against the values written.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

#include "io_test_util.h"
#include "tests/sim/cdr_writer.h"
#include "tests/sim/mcap_writer.h"
#include "worker/io/bag/bag_reader.h"
#include "worker/io/bag/rosbag2_reader.h"
#include "worker/io/gnss_csv.h"

namespace keel::io {
namespace {

using testing::expect_error;
using testing::TempDir;
using testing::write_text;

constexpr TimeNs kT0 = 1700000000LL * 1000000000LL;
constexpr int kStatuses[5] = {0, 1, 2, -1, 0};
constexpr int kCovarianceTypes[5] = {2, 0, 3, 0, 1};

// What make_gnss_bag.py writes (and write_fix_mcap below).
void expect_written_fixes(const GnssSeries& fixes) {
  ASSERT_EQ(fixes.size(), 5u);
  for (size_t i = 0; i < 5; ++i) {
    const GnssSample& s = fixes[i];
    EXPECT_EQ(s.t_ns, kT0 + static_cast<TimeNs>(i) * 1000000000LL);
    EXPECT_EQ(s.status, kStatuses[i]);
    if (kStatuses[i] < 0) {
      EXPECT_TRUE(std::isnan(s.latitude_deg));
      EXPECT_FALSE(s.covariance_known);
      continue;
    }
    EXPECT_DOUBLE_EQ(s.latitude_deg, 53.5 + 1e-5 * i);
    EXPECT_DOUBLE_EQ(s.longitude_deg, 9.9 + 2e-5 * i);
    EXPECT_DOUBLE_EQ(s.height_m, 40.0 + i);
    EXPECT_EQ(s.covariance_known, kCovarianceTypes[i] != 0) << i;
    if (s.covariance_known) {
      EXPECT_EQ(s.covariance_enu_m2[0], 0.25);
      EXPECT_EQ(s.covariance_enu_m2[4], 0.36);
      EXPECT_EQ(s.covariance_enu_m2[8], 1.0);
    }
  }
}

TEST(GnssCsv, ReadsFixesNoFixRowsAndSigmas) {
  TempDir dir;
  write_text(dir / "gnss.csv",
             "t,latitude,longitude,height,status,sigma_e,sigma_n,sigma_u\n"
             "1700000000.0,53.5,9.9,40,0,0.5,0.6,1.0\n"
             "1700000001.0,nan,nan,nan,-1,nan,nan,nan\n"
             "1700000002.0,53.50002,9.90004,42,2,nan,nan,nan\n");
  const GnssSeries fixes = read_gnss_csv(dir / "gnss.csv");
  ASSERT_EQ(fixes.size(), 3u);
  EXPECT_EQ(fixes[0].t_ns, kT0);
  EXPECT_TRUE(fixes[0].covariance_known);
  EXPECT_DOUBLE_EQ(fixes[0].covariance_enu_m2[0], 0.25);
  EXPECT_DOUBLE_EQ(fixes[0].covariance_enu_m2[4], 0.36);
  EXPECT_DOUBLE_EQ(fixes[0].covariance_enu_m2[8], 1.0);
  EXPECT_EQ(fixes[1].status, -1);
  EXPECT_FALSE(fixes[1].covariance_known);
  EXPECT_EQ(fixes[2].status, 2);
  EXPECT_FALSE(fixes[2].covariance_known);
  EXPECT_DOUBLE_EQ(fixes[2].longitude_deg, 9.90004);

  // Written and read back: the same samples.
  write_gnss_csv(dir / "back.csv", fixes, true);
  const GnssSeries back = read_gnss_csv(dir / "back.csv");
  ASSERT_EQ(back.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(back[i].t_ns, fixes[i].t_ns);
    EXPECT_EQ(back[i].status, fixes[i].status);
    EXPECT_EQ(back[i].covariance_known, fixes[i].covariance_known);
    EXPECT_EQ(back[i].covariance_enu_m2, fixes[i].covariance_enu_m2);
  }
  EXPECT_DOUBLE_EQ(back[2].latitude_deg, 53.50002);
}

TEST(GnssCsv, ErrorsNameFileLineAndColumn) {
  TempDir dir;
  const auto bad = [&](const std::string& body, std::initializer_list<std::string> needles) {
    write_text(dir / "g.csv", body);
    expect_error([&] { read_gnss_csv(dir / "g.csv"); }, needles);
  };
  bad("t,latitude,longitude,height,status\n1,53,9,0,3\n", {"g.csv:2:", "status"});
  bad("t,latitude,longitude,height,status\n1,nan,9,0,0\n", {"g.csv:2:", "latitude"});
  bad("t,latitude,longitude,height,status\n1,95,9,0,0\n", {"g.csv", "latitude", "[-90, 90]"});
  bad("t,latitude,longitude,height,status\n2,53,9,0,0\n1,53,9,0,0\n", {"g.csv:3:"});
  bad("t,latitude,longitude,height,status,sigma_e,sigma_n,sigma_u\n1,53,9,0,0,1,nan,1\n",
      {"g.csv", "all finite or all nan"});
  bad("t,latitude,longitude,height,status,sigma_e,sigma_n,sigma_u\n1,53,9,0,0,1,-1,1\n",
      {"g.csv", "negative"});
  bad("t,lat,lon,height,status\n", {"g.csv", "latitude"});
}

TEST(GnssBag, Ros1NavSatFixWithStatusAndCovarianceType) {
  TempDir dir;
  const auto bag = dir / "fix.bag";
  const std::string command = std::string("/usr/bin/python3 ") + KEEL_SOURCE_DIR +
                              "/tests/worker/io/make_gnss_bag.py " + bag.string();
  if (std::system(command.c_str()) != 0)
    GTEST_SKIP() << "/usr/bin/python3 with python3-rosbag and python3-sensor-msgs unavailable";
  const BagReader reader(bag);
  expect_written_fixes(reader.read_gnss("/fix"));
  expect_error([&] { reader.read_imu("/fix"); }, {"/fix", "sensor_msgs/NavSatFix"});
}

std::vector<uint8_t> fix_cdr(TimeNs t_ns, int status, double lat, double lon, double alt,
                             int covariance_type) {
  sim::CdrWriter w;
  w.i32(static_cast<int32_t>(t_ns / 1000000000));
  w.u32(static_cast<uint32_t>(t_ns % 1000000000));
  w.string("gnss");
  w.u8(static_cast<uint8_t>(static_cast<int8_t>(status)));
  w.u16(1);  // SERVICE_GPS
  w.f64(lat), w.f64(lon), w.f64(alt);
  for (double c : {0.25, 0.0, 0.0, 0.0, 0.36, 0.0, 0.0, 0.0, 1.0}) w.f64(c);
  w.u8(static_cast<uint8_t>(covariance_type));
  return w.take();
}

TEST(GnssBag, Ros2NavSatFixWithStatusAndCovarianceType) {
  TempDir dir;
  const auto file = dir / "fix.mcap";
  {
    sim::McapWriter w(file.string(), {"", 4096});
    const uint16_t fix =
        w.add_channel("/fix", w.add_schema("sensor_msgs/msg/NavSatFix", "ros2msg", ""));
    for (int i = 0; i < 5; ++i) {
      const TimeNs t = kT0 + i * 1000000000LL;
      const bool no_fix = kStatuses[i] < 0;
      w.write(fix, t,
              fix_cdr(t, kStatuses[i], no_fix ? NAN : 53.5 + 1e-5 * i,
                      no_fix ? NAN : 9.9 + 2e-5 * i, no_fix ? NAN : 40.0 + i, kCovarianceTypes[i]));
    }
    w.close();
  }
  const Rosbag2Reader reader(file);
  expect_written_fixes(reader.read_gnss("/fix"));
}

TEST(GnssBag, Ros2FixOutOfRangeOrCutShortIsNamed) {
  TempDir dir;
  const auto write = [&](const std::vector<uint8_t>& message) {
    const auto file = dir / "bad.mcap";
    sim::McapWriter w(file.string(), {"", 4096});
    const uint16_t fix =
        w.add_channel("/fix", w.add_schema("sensor_msgs/msg/NavSatFix", "ros2msg", ""));
    w.write(fix, kT0, message);
    w.close();
    return file;
  };
  const Rosbag2Reader far(write(fix_cdr(kT0, 0, 91.0, 9.9, 0.0, 0)));
  expect_error([&] { far.read_gnss("/fix"); }, {"bad.mcap", "/fix", "message 0", "latitude"});
  const Rosbag2Reader status(write(fix_cdr(kT0, 5, 53.0, 9.9, 0.0, 0)));
  expect_error([&] { status.read_gnss("/fix"); }, {"/fix", "message 0", "status"});
  std::vector<uint8_t> cut = fix_cdr(kT0, 0, 53.0, 9.9, 0.0, 0);
  cut.resize(cut.size() - 20);
  const Rosbag2Reader short_message(write(cut));
  expect_error([&] { short_message.read_gnss("/fix"); },
               {"/fix", "message 0", "position_covariance"});
}

}  // namespace
}  // namespace keel::io
