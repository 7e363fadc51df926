#include "worker/io/tum.h"

#include <gtest/gtest.h>

#include "io_test_util.h"

namespace keel::io {
namespace {

using testing::expect_error;
using testing::TempDir;
using testing::write_text;

TEST(Tum, RoundTripKeepsPosesAndStamps) {
  TempDir dir;
  Trajectory written;
  for (int i = 0; i < 50; ++i) {
    const Eigen::Quaterniond q(Eigen::AngleAxisd(0.1 * i, Eigen::Vector3d(1, 2, 3).normalized()));
    written.push_back({1700000000000000001LL + i * 100000000LL,
                       make_pose(q, Eigen::Vector3d(i, -0.5 * i, 0.25))});
  }
  write_tum(dir / "t.tum", written);
  const Trajectory read = read_tum(dir / "t.tum");
  ASSERT_EQ(read.size(), written.size());
  for (size_t i = 0; i < read.size(); ++i) {
    EXPECT_EQ(read[i].t_ns, written[i].t_ns);
    EXPECT_TRUE(read[i].T_world_body.isApprox(written[i].T_world_body, 1e-12));
  }
}

TEST(Tum, HandWrittenLinesWithCommentsAndTabs) {
  TempDir dir;
  // 90 degrees about z: q = (0, 0, sin 45, cos 45), written with few digits (normalised on read).
  write_text(dir / "t.tum",
             "# t x y z qx qy qz qw\n\n1.5 1 2 3 0 0 0 1\n2.0\t4 5 6\t0 0 0.7071 0.7071\n");
  const Trajectory read = read_tum(dir / "t.tum");
  ASSERT_EQ(read.size(), 2u);
  EXPECT_EQ(read[0].t_ns, 1500000000LL);
  EXPECT_EQ(read[1].T_world_body.translation(), Eigen::Vector3d(4, 5, 6));
  const Eigen::Vector3d x_rotated = read[1].T_world_body.linear() * Eigen::Vector3d::UnitX();
  EXPECT_NEAR(x_rotated.y(), 1.0, 1e-12);
  EXPECT_NEAR(Eigen::Quaterniond(read[1].T_world_body.linear()).norm(), 1.0, 1e-12);
}

TEST(Tum, BadQuaternionNamesLine) {
  TempDir dir;
  write_text(dir / "t.tum", "1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 0.5 0.5\n");
  expect_error([&] { read_tum(dir / "t.tum"); }, {"t.tum:2:", "unit norm"});
}

TEST(Tum, NanUnsortedAndShortLinesNameLine) {
  TempDir dir;
  write_text(dir / "nan.tum", "1.0 0 nan 0 0 0 0 1\n");
  expect_error([&] { read_tum(dir / "nan.tum"); }, {"nan.tum:1:", "y:", "finite"});
  write_text(dir / "unsorted.tum", "# c\n2.0 0 0 0 0 0 0 1\n1.0 0 0 0 0 0 0 1\n");
  expect_error([&] { read_tum(dir / "unsorted.tum"); }, {"unsorted.tum:3:", "decreasing"});
  write_text(dir / "short.tum", "1.0 0 0 0 0 0 1\n");
  expect_error([&] { read_tum(dir / "short.tum"); },
               {"short.tum:1:", "expected 8 values", "found 7"});
}

}  // namespace
}  // namespace keel::io
