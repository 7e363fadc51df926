// Ingest on a mission whose DVL is a Water Linked A50 topic: invalid samples (velocity invalid
// and fewer than three beams) and three-beam solutions are counted in the sensor's report.
#include <gtest/gtest.h>

#include "io_test_util.h"
#include "tests/sim/bag2_writer.h"
#include "tests/sim/bag_writer.h"
#include "worker/io/dvl_beams.h"
#include "worker/stages/ingest/stage.h"

namespace keel::pipeline {
namespace {

using io::testing::TempDir;

// 40 messages at 10 Hz: every 5th has its velocity invalid and one beam dropped (three-beam
// solution), every 7th has it invalid with two beams (invalid); the rest are valid.
std::vector<io::A50Dvl> messages(size_t& invalid, size_t& three_beam) {
  std::vector<io::A50Dvl> out;
  invalid = three_beam = 0;
  const auto b = io::a50_beam_directions();
  const Eigen::Vector3d v(0.2, 0.05, 0.0);
  for (int k = 0; k < 40; ++k) {
    io::A50Dvl m;
    m.stamp_ns = 1700000000LL * 1000000000LL + k * 100000000LL;
    m.velocity_m_s = v;
    m.fom_m_s = 0.002;
    m.velocity_valid = true;
    for (int i = 0; i < 4; ++i) m.beams.push_back({i, b[i].dot(v), 2.0, -30, -90, true});
    if (k % 7 == 3) {
      m.velocity_valid = false;
      m.beams[0].valid = m.beams[1].valid = false;
      ++invalid;
    } else if (k % 5 == 1) {
      m.velocity_valid = false;
      m.beams[k % 4].valid = false;
      ++three_beam;
    }
    out.push_back(m);
  }
  return out;
}

void expect_counts(const std::filesystem::path& dir, size_t invalid, size_t three_beam) {
  StageContext context;
  context.mission_dir = dir;
  context.work_dir = dir;
  const StageResult result = make_ingest_stage()->run(context);
  const auto& dvl = result.report["sensors"]["dvl"];
  EXPECT_EQ(dvl["count"], 40);
  EXPECT_EQ(dvl["invalid"], invalid);
  EXPECT_EQ(dvl["three_beam"], three_beam);
  EXPECT_DOUBLE_EQ(dvl["fom_m_s"]["mean"].get<double>(), 0.002);
}

TEST(IngestA50, CountsInvalidAndThreeBeamSamplesFromRos1AndRos2Bags) {
  size_t invalid = 0, three_beam = 0;
  const auto all = messages(invalid, three_beam);
  ASSERT_GT(invalid, 0u);
  ASSERT_GT(three_beam, 0u);
  for (const std::string bag : {"mission.bag", "mission_ros2"}) {
    SCOPED_TRACE(bag);
    TempDir dir;
    if (bag == "mission.bag") {
      sim::BagWriter writer((dir / bag).string());
      for (const auto& m : all) writer.a50_dvl("/dvl/data", "dvl_link", m);
      writer.close();
    } else {
      sim::Bag2Writer writer((dir / bag).string(), sim::Bag2Options{});
      for (const auto& m : all) writer.a50_dvl("/dvl/data", "dvl_link", m);
      writer.close();
    }
    io::testing::write_text(dir / "mission.yaml",
                            "keel_mission: 1\nname: a50\nbag: " + bag +
                                "\nsensors:\n  - {name: dvl, type: dvl, topic: /dvl/data, "
                                "rate_hz: 10}\n");
    expect_counts(dir.path(), invalid, three_beam);
  }
}

}  // namespace
}  // namespace keel::pipeline
