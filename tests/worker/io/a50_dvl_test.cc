// Water Linked A50 messages written into ROS1 and ROS 2 bags by keel-sim's writers, read back
// through BagSource: the published velocity when valid, the beams' least-squares velocity
// (against the Janus closed forms) when not, invalid samples with fewer than three beams.
#include "worker/io/bag/a50_dvl_sample.h"

#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>

#include <cmath>
#include <cstring>

#include "io_test_util.h"
#include "tests/sim/bag2_writer.h"
#include "tests/sim/bag_writer.h"
#include "worker/io/bag/a50_messages.h"
#include "worker/io/bag/bag_format_error.h"
#include "worker/io/bag/bag_source.h"
#include "worker/io/bag/rosbag2_reader.h"
#include "worker/io/dvl_beams.h"
#include "worker/io/io_error.h"

namespace keel::io {
namespace {

using testing::TempDir;

constexpr TimeNs kT0 = 1700000000LL * 1000000000LL;
const double kTilt = kA50BeamTiltDeg * M_PI / 180.0;

// Beams of velocity v (b . v) in azimuth order 45, 135, 225, 315 degrees, i.e. A50 transducer
// ids 3, 0, 1, 2 (the reader places beams by id, not by position); validity from `valid`.
std::vector<A50Beam> beams_of(const Eigen::Vector3d& v, std::array<bool, 4> valid) {
  std::vector<A50Beam> out;
  const auto b = a50_beam_directions();
  for (int j = 0; j < 4; ++j) {
    const int id = (j + 3) % 4;
    out.push_back({id, b[id].dot(v), 1.5 + 0.1 * j, -30.0 - j, -90.0 + j, valid[j]});
  }
  return out;
}

struct Case {
  A50Dvl message;
  bool valid;
  int beams_used;
  Eigen::Vector3d expected;
};

// 0: valid velocity; 1: invalid, four beams; 2-5: invalid, beam 0..3 dropped (closed form of
// the three-beam Janus solution); 6: invalid, two beams; 7: valid, no beams; 8: invalid, none.
std::vector<Case> cases() {
  std::vector<Case> out;
  const Eigen::Vector3d published(0.31, -0.12, 0.04);
  auto message = [&](int k, bool velocity_valid, std::vector<A50Beam> beams) {
    A50Dvl m;
    m.stamp_ns = kT0 + k * 100000000LL;
    m.time_ms = 100.0 + k;
    m.velocity_m_s = published + Eigen::Vector3d(0.01 * k, 0, 0);
    m.fom_m_s = 0.002 + 0.001 * k;
    for (int i = 0; i < 9; ++i) m.covariance_m2_s2[i] = i % 4 == 0 ? 1e-5 * (k + 1) : 1e-7 * i;
    m.altitude_m = 2.0 + k;
    m.beams = std::move(beams);
    m.velocity_valid = velocity_valid;
    m.status = k % 2;
    return m;
  };
  const Eigen::Vector3d v(-0.5, 0.25, 0.1);
  out.push_back({message(0, true, beams_of(v, {1, 1, 1, 1})), true, 0, published});
  out.push_back({message(1, false, beams_of(v, {1, 1, 1, 1})), true, 4, v});
  const double s = std::sin(kTilt), c = std::cos(kTilt), r2 = std::sqrt(2.0);
  for (int dropped = 0; dropped < 4; ++dropped) {
    std::array<bool, 4> valid = {1, 1, 1, 1};
    valid[dropped] = false;
    auto beams = beams_of(v, valid);
    // Noise on the used beams, so the three-beam solution differs from v; the dropped beam
    // carries a garbage velocity that must not matter.
    const double noise[4] = {0.004, -0.003, 0.002, -0.005};
    for (int k = 0; k < 4; ++k) beams[k].velocity_m_s += k == dropped ? 7.0 : noise[k];
    double r[4];
    for (int k = 0; k < 4; ++k) r[k] = beams[k].velocity_m_s;
    // Closed forms with beam `dropped` missing (b_j = (s cos a_j, s sin a_j, c),
    // a_j = 45 + 90 j degrees): each solves the three remaining equations exactly.
    Eigen::Vector3d closed;
    switch (dropped) {
      case 0:
        closed = {(r[3] - r[2]) / (r2 * s), (r[1] - r[2]) / (r2 * s), (r[1] + r[3]) / (2 * c)};
        break;
      case 1:
        closed = {(r[3] - r[2]) / (r2 * s), (r[0] - r[3]) / (r2 * s), (r[0] + r[2]) / (2 * c)};
        break;
      case 2:
        closed = {(r[0] - r[1]) / (r2 * s), (r[0] - r[3]) / (r2 * s), (r[1] + r[3]) / (2 * c)};
        break;
      default:
        closed = {(r[0] - r[1]) / (r2 * s), (r[1] - r[2]) / (r2 * s), (r[0] + r[2]) / (2 * c)};
        break;
    }
    out.push_back({message(2 + dropped, false, beams), true, 3, closed});
  }
  out.push_back({message(6, false, beams_of(v, {1, 0, 1, 0})), false, 0, Eigen::Vector3d::Zero()});
  out.push_back({message(7, true, {}), true, 0, published + Eigen::Vector3d(0.07, 0, 0)});
  out.push_back({message(8, false, {}), false, 0, Eigen::Vector3d::Zero()});
  out[0].expected = out[0].message.velocity_m_s;
  return out;
}

void expect_series(const DvlSeries& series, const std::vector<Case>& cases) {
  ASSERT_EQ(series.size(), cases.size());
  for (size_t k = 0; k < cases.size(); ++k) {
    SCOPED_TRACE("message " + std::to_string(k));
    const DvlSample& s = series[k];
    EXPECT_EQ(s.t_ns, cases[k].message.stamp_ns);
    EXPECT_EQ(s.valid, cases[k].valid);
    EXPECT_EQ(s.beams_used, cases[k].beams_used);
    if (cases[k].valid) {
      EXPECT_LT((s.velocity_m_s - cases[k].expected).norm(), 1e-12);
    }
    if (cases[k].message.velocity_valid)
      EXPECT_EQ(s.fom_m_s, cases[k].message.fom_m_s);
    else
      EXPECT_TRUE(std::isnan(s.fom_m_s));
  }
}

TEST(A50Dvl, Ros1BagRoundTrip) {
  TempDir dir;
  const auto all = cases();
  {
    sim::BagWriter writer((dir / "a50.bag").string());
    for (const Case& c : all) writer.a50_dvl("/dvl/data", "dvl_link", c.message);
    writer.close();
  }
  const auto bag = open_bag(dir / "a50.bag");
  EXPECT_EQ(bag->topic("/dvl/data").datatype, "waterlinked_a50_ros_driver/DVL");
  expect_series(bag->read_dvl("/dvl/data"), all);
}

class A50Ros2 : public ::testing::TestWithParam<std::string> {};

TEST_P(A50Ros2, BagRoundTrip) {
  TempDir dir;
  const auto all = cases();
  {
    sim::Bag2Options options;
    options.storage = GetParam();
    sim::Bag2Writer writer((dir / "a50").string(), options);
    for (const Case& c : all) writer.a50_dvl("/dvl/data", "dvl_link", c.message);
    writer.close();
  }
  const auto bag = open_bag(dir / "a50");
  EXPECT_EQ(bag->topic("/dvl/data").datatype, "dvl_msgs/msg/DVL");
  expect_series(bag->read_dvl("/dvl/data"), all);
  // Every field as written.
  Rosbag2Reader reader(dir / "a50");
  size_t n = 0;
  reader.for_each_message("/dvl/data", [&](const Rosbag2Reader::RawMessage& raw, size_t i) {
    const A50Dvl m = decode_a50_ros2(raw.data, raw.size);
    const A50Dvl& w = all[i].message;
    EXPECT_EQ(m.stamp_ns, w.stamp_ns);
    EXPECT_EQ(m.time_ms, w.time_ms);
    EXPECT_EQ(m.velocity_m_s, w.velocity_m_s);
    EXPECT_EQ(m.fom_m_s, w.fom_m_s);
    EXPECT_TRUE(m.has_covariance);
    EXPECT_EQ(m.covariance_m2_s2, w.covariance_m2_s2);
    EXPECT_EQ(m.altitude_m, w.altitude_m);
    ASSERT_EQ(m.beams.size(), w.beams.size());
    for (size_t k = 0; k < m.beams.size(); ++k) {
      EXPECT_EQ(m.beams[k].id, w.beams[k].id);
      EXPECT_EQ(m.beams[k].velocity_m_s, w.beams[k].velocity_m_s);
      EXPECT_EQ(m.beams[k].distance_m, w.beams[k].distance_m);
      EXPECT_EQ(m.beams[k].rssi_dbm, w.beams[k].rssi_dbm);
      EXPECT_EQ(m.beams[k].nsd_dbm, w.beams[k].nsd_dbm);
      EXPECT_EQ(m.beams[k].valid, w.beams[k].valid);
    }
    EXPECT_EQ(m.velocity_valid, w.velocity_valid);
    EXPECT_EQ(m.status, w.status);
    // Cut short within the fields read (status ends 28 bytes before the end: two int64 and
    // the form string follow), the message is refused naming a field.
    for (size_t size : {raw.size / 2, raw.size - 29}) {
      try {
        decode_a50_ros2(raw.data, size);
        ADD_FAILURE() << "a " << size << "-byte prefix decoded";
      } catch (const BagFormatError& e) {
        EXPECT_NE(std::string(e.what()).find("field '"), std::string::npos) << e.what();
      }
    }
    ++n;
  });
  EXPECT_EQ(n, all.size());
}

INSTANTIATE_TEST_SUITE_P(Storages, A50Ros2, ::testing::Values("mcap", "sqlite3"));

TEST(A50Dvl, Ros1BytesAreBoundsChecked) {
  // A header, then a beams count of 2^32 - 1 that the message cannot hold.
  std::vector<uint8_t> bytes(12 + 4 + 8 * 6, 0);
  const uint32_t huge = 0xffffffffu;
  bytes.resize(bytes.size() + 4);
  std::memcpy(bytes.data() + bytes.size() - 4, &huge, 4);
  try {
    decode_a50_ros1(bytes.data(), bytes.size());
    FAIL() << "decoded";
  } catch (const BagFormatError& e) {
    EXPECT_NE(std::string(e.what()).find("field 'beams'"), std::string::npos) << e.what();
  }
  EXPECT_THROW(decode_a50_ros1(bytes.data(), 7), BagFormatError);
}

TEST(A50Dvl, BadBeamIdsAndNonFiniteVelocitiesAreRefusedNamingTheMessage) {
  A50Dvl m;
  m.beams = beams_of({0.1, 0.2, 0.3}, {1, 1, 1, 1});
  m.beams[2].id = 9;
  try {
    a50_dvl_sample(m, 1, "a.bag: topic '/dvl' message 3");
    FAIL() << "accepted";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("message 3 beams[2].id is 9"), std::string::npos)
        << e.what();
  }
  m.beams[2].id = m.beams[0].id;
  EXPECT_THROW(a50_dvl_sample(m, 1, "x"), IoError);  // id 1 twice
  A50Dvl nan;
  nan.velocity_valid = true;
  nan.velocity_m_s.x() = std::nan("");
  EXPECT_THROW(a50_dvl_sample(nan, 1, "x"), IoError);
}

// Water Linked's own A50 recordings (github.com/waterlinked/dvl-a50-ros-driver, data/01-06 at
// commit e09ad0a; never part of this repository): KEEL_A50_BAGS names the folder holding them.
// Counts per bag from Debian's python3-rosbag (an independent reader): messages, invalid
// (velocity_valid false and < 3 valid beams), velocity_valid false with exactly 3 beams.
TEST(A50Dvl, WaterLinkedRecordings) {
  const char* folder = std::getenv("KEEL_A50_BAGS");
  if (!folder || !*folder)
    GTEST_SKIP() << "KEEL_A50_BAGS is not set (a folder with Water Linked's A50 bags: "
                    "dvl.bag, dvl_circle.bag, dvl_fast_rectangle.bag, dvl_slow_rectangle.bag)";
  struct Expected {
    const char* bag;
    size_t messages, invalid, three_beam;
  };
  const Expected expected[] = {{"dvl.bag", 1423, 29, 1},
                               {"dvl_circle.bag", 378, 16, 7},
                               {"dvl_fast_rectangle.bag", 395, 4, 0},
                               {"dvl_slow_rectangle.bag", 457, 8, 1}};
  std::vector<double> differences, foms;
  for (const Expected& e : expected) {
    SCOPED_TRACE(e.bag);
    const std::filesystem::path path = std::filesystem::path(folder) / e.bag;
    const DvlSeries series = open_bag(path)->read_dvl("/dvl/data");
    ASSERT_EQ(series.size(), e.messages);
    EXPECT_EQ(size_t(std::count_if(series.begin(), series.end(),
                                   [](const DvlSample& x) { return !x.valid; })),
              e.invalid);
    EXPECT_EQ(size_t(std::count_if(series.begin(), series.end(),
                                   [](const DvlSample& x) { return x.beams_used == 3; })),
              e.three_beam);
    // The beam geometry: the velocity solved from four beams against the A50's own.
    rosbag::Bag bag(path.string());
    for (const rosbag::MessageInstance& m : rosbag::View(bag, rosbag::TopicQuery("/dvl/data"))) {
      std::vector<uint8_t> bytes(m.size());
      ros::serialization::OStream out(bytes.data(), static_cast<uint32_t>(bytes.size()));
      m.write(out);
      A50Dvl message = decode_a50_ros1(bytes.data(), bytes.size());
      if (!message.velocity_valid || message.beams.size() != 4) continue;
      if (!std::all_of(message.beams.begin(), message.beams.end(),
                       [](const A50Beam& b) { return b.valid; }))
        continue;
      message.velocity_valid = false;
      const DvlSample s = a50_dvl_sample(message, 1, e.bag);
      ASSERT_EQ(s.beams_used, 4);
      differences.push_back((s.velocity_m_s - message.velocity_m_s).norm());
      foms.push_back(message.fom_m_s);
    }
  }
  ASSERT_GT(differences.size(), 2000u);
  auto median = [](std::vector<double> x) {
    std::nth_element(x.begin(), x.begin() + x.size() / 2, x.end());
    return x[x.size() / 2];
  };
  // The A50 weighs its beams itself; equal weights agree to about its figure of merit. A wrong
  // beam assignment (a mirrored or rotated array) differs by 18 mm/s or more.
  EXPECT_LT(median(differences), 1.5 * median(foms));
  EXPECT_LT(median(differences), 0.003);
}

}  // namespace
}  // namespace keel::io
