#include "tests/sim/slam_recording.h"

#include <gtest/gtest.h>

#include "tests/sim/scenarios.h"

namespace keel::sim {
namespace {

// The recorded odometry must give refinement something to correct: its error against the
// truth exceeds the MAP poses' error, on every seed.
TEST(SlamRecording, OdometryDriftsMoreThanMapPoses) {
  for (uint64_t seed : {1, 2, 3}) {
    const Scenario s = make_scenario("usv-bridge", seed);
    const double duration = s.default_duration_s;
    const PoseTable truth(*s.motion, duration);
    const Trajectory odometry = simulate_odometry(truth, duration, 0, {}, seed);
    const Trajectory map = simulate_map_poses(truth, duration, 0, {}, seed);
    EXPECT_NEAR(map.size(), duration, 2.0);            // ~1 Hz keyframes
    EXPECT_NEAR(odometry.size(), duration * 10, 2.0);  // 10 Hz
    const double odometry_rmse = position_rmse(odometry, truth, 0);
    const double map_rmse = position_rmse(map, truth, 0);
    EXPECT_GT(odometry_rmse, 2.0 * map_rmse) << seed;
    EXPECT_LT(map_rmse, 0.1);
    // "A few % of distance": final drift between 0.2 % and 10 % of the path.
    const double final_error =
        (odometry.back().T_world_body.translation() - truth.T_world_body(duration).translation())
            .norm();
    EXPECT_GT(final_error, 0.002 * s.motion->path().length());
    EXPECT_LT(final_error, 0.10 * s.motion->path().length());
  }
}

// In the corridor the odometry loses motion along the corridor axis (world x).
TEST(SlamRecording, CorridorOdometryDriftsAlongTheAxis) {
  const Scenario s = make_scenario("usv-corridor", 8);
  const double duration = s.default_duration_s;
  const PoseTable truth(*s.motion, duration);
  OdometryOptions options;
  options.degenerate_axis_world = s.degenerate_axis_world;
  const Trajectory odometry = simulate_odometry(truth, duration, 0, options, 8);
  const Eigen::Vector3d error =
      odometry.back().T_world_body.translation() - truth.T_world_body(duration).translation();
  EXPECT_GT(std::abs(error.x()), 3.0);  // ~40 % of ~36 m along the axis
  EXPECT_GT(std::abs(error.x()), 3.0 * std::abs(error.y()));
}

}  // namespace
}  // namespace keel::sim
