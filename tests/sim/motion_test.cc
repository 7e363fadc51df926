#include "tests/sim/motion.h"

#include <gtest/gtest.h>

#include "tests/sim/scenarios.h"

namespace keel::sim {
namespace {

// Seed 000 Sec. V-C: Environment 1 is ~265 m at 1.2 m/s, returning to the start.
TEST(Motion, BridgePathMatchesSpecAndReturnsToStart) {
  const Scenario s = make_scenario("usv-bridge", 7);
  const PathMotion& m = *s.motion;
  EXPECT_NEAR(m.path().length(), 265.0, 15.0);
  EXPECT_NEAR(m.end_time(), 225.0, 10.0);
  const KinematicState start = m.state(0.0), mid = m.state(100.0),
                       end = m.state(m.end_time() + 1.0);
  EXPECT_NEAR(mid.v_world.head<2>().norm(), 1.2, 0.01);
  EXPECT_LT((end.p_world - start.p_world).head<2>().norm(), 3.0);
  EXPECT_LT(end.v_world.head<2>().norm(), 1e-9);  // at rest at the end
  EXPECT_LT(start.v_world.head<2>().norm(), 1e-9);
}

TEST(Motion, CorridorPathIsAbout38Metres) {
  const Scenario s = make_scenario("usv-corridor", 7);
  EXPECT_NEAR(s.motion->path().length(), 38.0, 1.5);
}

// Velocity, acceleration and body rate are analytic; check them against central differences.
TEST(Motion, DerivativesMatchNumericalDifferences) {
  for (const char* name : {"usv-bridge", "hauv-hull"}) {
    const Scenario s = make_scenario(name, 3);
    const PathMotion& m = *s.motion;
    const double h = 1e-4;
    for (double t : {1.0, 3.1, 20.0, 57.3, 100.0}) {
      const KinematicState a = m.state(t - h), b = m.state(t), c = m.state(t + h);
      const Eigen::Vector3d v_num = (c.p_world - a.p_world) / (2 * h);
      const Eigen::Vector3d a_num = (c.v_world - a.v_world) / (2 * h);
      EXPECT_LT((v_num - b.v_world).norm(), 1e-6) << name << " t=" << t;
      EXPECT_LT((a_num - b.a_world).norm(), 1e-4) << name << " t=" << t;
      // omega_body: R(t)^T R(t+h) = Exp(omega h) to first order.
      const Eigen::AngleAxisd d(a.q_world_body.conjugate() * c.q_world_body);
      const Eigen::Vector3d w_num = d.axis() * d.angle() / (2 * h);
      EXPECT_LT((w_num - b.omega_body).norm(), 1e-6) << name << " t=" << t;
    }
  }
}

}  // namespace
}  // namespace keel::sim
