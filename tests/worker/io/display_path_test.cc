#include "worker/io/display_path.h"

#include <gtest/gtest.h>

namespace keel::io {
namespace {

TEST(DisplayPath, NamesFilesRelativeToTheInnermostRoot) {
  EXPECT_EQ(display_path("/cache/jobs/j_1/mission/imu.csv"), "/cache/jobs/j_1/mission/imu.csv");
  {
    const DisplayRoots roots({"/cache/jobs/j_1/mission", "/cache/jobs/j_1/cad/hull.ply"});
    EXPECT_EQ(display_path("/cache/jobs/j_1/mission/imu.csv"), "imu.csv");
    EXPECT_EQ(display_path("/cache/jobs/j_1/mission/./lidar_h/000001.pcd"), "lidar_h/000001.pcd");
    EXPECT_EQ(display_path("/cache/jobs/j_1/cad/hull.ply"), "hull.ply");  // a file root
    EXPECT_EQ(display_path("/cache/jobs/j_1/missionary/x"), "/cache/jobs/j_1/missionary/x");
    EXPECT_EQ(display_path("/elsewhere/imu.csv"), "/elsewhere/imu.csv");
    {
      const DisplayRoots inner({"/cache/jobs/j_1/mission/lidar_h"});
      EXPECT_EQ(display_path("/cache/jobs/j_1/mission/lidar_h/000001.pcd"), "000001.pcd");
      EXPECT_EQ(display_path("/cache/jobs/j_1/mission/imu.csv"), "imu.csv");
    }
    EXPECT_EQ(display_path("/cache/jobs/j_1/mission/lidar_h/000001.pcd"), "lidar_h/000001.pcd");
  }
  EXPECT_EQ(display_path("/cache/jobs/j_1/mission/imu.csv"), "/cache/jobs/j_1/mission/imu.csv");
}

}  // namespace
}  // namespace keel::io
