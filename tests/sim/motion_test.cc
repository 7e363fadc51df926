#include "tests/sim/motion.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <string>

#include "tests/sim/scenarios.h"
#include "tests/sim/simulator.h"

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

// ---- repeated laps (motion.laps) ------------------------------------------------------------

constexpr size_t kBridgeWaypoints = 32, kTurnaroundWaypoints = 5;

Scenario bridge_laps(int laps, uint64_t seed = 3) {
  ScenarioOptions options;
  options.motion.laps = laps;
  return make_scenario("usv-bridge", seed, options);
}

// Arc length where lap k (0-based) starts: its first waypoint.
double lap_start_s(const SmoothPath& path, int k) {
  return path.waypoint_arc_length(k * (kBridgeWaypoints + kTurnaroundWaypoints));
}

TEST(MotionLaps, OneLapIsTheLapItself) {
  const std::vector<Eigen::Vector3d> lap = {{0, 0, 0}, {1, 0, 0}, {2, 1, 0}};
  const std::vector<Eigen::Vector3d> connector = {{3, 3, 0}};
  EXPECT_EQ(repeat_laps(lap, connector, 1), lap);
  const auto three = repeat_laps(lap, connector, 3);
  ASSERT_EQ(three.size(), 3 * lap.size() + 2 * connector.size());
  EXPECT_EQ(three[3], connector[0]);
  EXPECT_EQ(three[4], lap[0]);
  EXPECT_EQ(three.back(), lap.back());
}

// Time at which the vehicle, cruising, reaches arc length s (between the two ramps).
double cruise_time_at(const PathMotion& m, double s) {
  const MotionOptions& o = m.options();
  return o.start_rest_s + o.ramp_s + (s - 0.5 * o.cruise_speed_mps * o.ramp_s) / o.cruise_speed_mps;
}

TEST(MotionLaps, LapsFlyTheSamePathWithoutStopping) {
  const Scenario one = bridge_laps(1), three = bridge_laps(3);
  const PathMotion &m1 = *one.motion, &m3 = *three.motion;
  const double speed = m3.options().cruise_speed_mps;
  // The end time grows by the extra path flown at cruise speed; the default duration follows.
  EXPECT_NEAR(m3.end_time() - m1.end_time(), (m3.path().length() - m1.path().length()) / speed,
              1e-9);
  EXPECT_EQ(three.default_duration_s, std::ceil(m3.end_time()));
  // Laps 2 and 3 each add the lap and one turn-around (tens of metres, not another lap).
  const double added_per_lap = (m3.path().length() - m1.path().length()) / 2.0;
  EXPECT_GT(added_per_lap, m1.path().length() + 15.0);
  EXPECT_LT(added_per_lap, m1.path().length() + 40.0);
  // Cruise speed from the first ramp's end to the last ramp's start: no stop between laps.
  const double cruise_from = m3.options().start_rest_s + m3.options().ramp_s;
  for (double t = cruise_from; t < m3.end_time() - m3.options().ramp_s; t += 0.25)
    ASSERT_NEAR(m3.state(t).v_world.head<2>().norm(), speed, 1e-9) << "t=" << t;
  EXPECT_LT(m3.state(m3.end_time()).v_world.head<2>().norm(), 1e-9);
  // Every lap starts where the single lap does.
  for (int k = 0; k < 3; ++k)
    EXPECT_LT((m3.path().at(lap_start_s(m3.path(), k)).p - m1.path().at(0.0).p).norm(), 1e-9);
  // Away from the turn-around (waypoints 3 .. N-4: from x = -54 round the bridge to x = -58),
  // every lap is the single lap's path: same point at the same arc length from waypoint 3.
  const SmoothPath &p1 = m1.path(), &p3 = m3.path();
  const double from1 = p1.waypoint_arc_length(3);
  const double span = p1.waypoint_arc_length(kBridgeWaypoints - 4) - from1;
  for (int k = 0; k < 3; ++k) {
    const double from3 = p3.waypoint_arc_length(k * (kBridgeWaypoints + kTurnaroundWaypoints) + 3);
    for (double d = 0.0; d <= span; d += 0.5)
      ASSERT_LT((p3.at(from3 + d).p - p1.at(from1 + d).p).norm(), 0.02)
          << "lap " << k << " d=" << d;
  }
}

TEST(MotionLaps, TurnAroundIsASmoothLoopBesideTheStart) {
  const Scenario two = bridge_laps(2);
  const SmoothPath& path = two.motion->path();
  const double from = path.waypoint_arc_length(kBridgeWaypoints - 1);
  const double to = path.waypoint_arc_length(kBridgeWaypoints + kTurnaroundWaypoints);
  double max_curvature = 0.0, min_x = 1e9, heading_change = 0.0;
  Eigen::Vector3d last_tangent = path.at(from).tangent;
  const int steps = int((to - from) / 0.01);
  for (int i = 1; i <= steps; ++i) {
    const SmoothPath::Point point = path.at(from + (to - from) * i / steps);
    max_curvature = std::max(max_curvature, point.d2p_ds2.norm());
    min_x = std::min(min_x, point.p.x());
    heading_change +=
        std::atan2(last_tangent.x() * point.tangent.y() - last_tangent.y() * point.tangent.x(),
                   last_tangent.dot(point.tangent));
    last_tangent = point.tangent;
  }
  EXPECT_GT(1.0 / max_curvature, 3.0);  // a turn of a few metres' radius, no kink
  EXPECT_GT(min_x, -101.0);             // west of the start, within the walls' extent
  // From heading ~west-north-west to east: a clockwise loop (the bulb swings left first).
  const double end_heading = std::atan2(path.at(from).tangent.y(), path.at(from).tangent.x());
  const double start_heading = std::atan2(path.at(to).tangent.y(), path.at(to).tangent.x());
  EXPECT_NEAR(std::remainder(end_heading + heading_change - start_heading, 2 * M_PI), 0.0, 1e-3);
  EXPECT_LT(heading_change, -M_PI);
}

// Velocity, acceleration and body rate across the lap joint, against central differences.
TEST(MotionLaps, DerivativesMatchNumericalDifferencesAcrossTheJoint) {
  const Scenario two = bridge_laps(2);
  const PathMotion& m = *two.motion;
  const double t0 = cruise_time_at(m, m.path().waypoint_arc_length(kBridgeWaypoints - 2));
  const double t1 =
      cruise_time_at(m, m.path().waypoint_arc_length(kBridgeWaypoints + kTurnaroundWaypoints + 1));
  ASSERT_LT(t1, m.end_time() - m.options().ramp_s);
  // The curvature's rate jumps at waypoints (the path is C2), so a difference straddling one is
  // only first-order accurate: a smaller step than above keeps that error below the bounds.
  const double h = 1e-5;
  for (double t = t0; t <= t1; t += (t1 - t0) / 40.0) {
    const KinematicState a = m.state(t - h), b = m.state(t), c = m.state(t + h);
    const Eigen::Vector3d v_num = (c.p_world - a.p_world) / (2 * h);
    const Eigen::Vector3d a_num = (c.v_world - a.v_world) / (2 * h);
    EXPECT_LT((v_num - b.v_world).norm(), 1e-6) << "t=" << t;
    EXPECT_LT((a_num - b.a_world).norm(), 1e-4) << "t=" << t;
    const Eigen::AngleAxisd d(a.q_world_body.conjugate() * c.q_world_body);
    const Eigen::Vector3d w_num = d.axis() * d.angle() / (2 * h);
    EXPECT_LT((w_num - b.omega_body).norm(), 1e-6) << "t=" << t;
    // The heading follows the path through the loop.
    const double yaw = std::atan2(b.v_world.y(), b.v_world.x());
    const Eigen::Vector3d x_body = b.q_world_body * Eigen::Vector3d::UnitX();
    EXPECT_NEAR(std::remainder(std::atan2(x_body.y(), x_body.x()) - yaw, 2 * M_PI), 0.0, 0.05)
        << "t=" << t;
  }
}

std::string error_of(const std::function<void()>& run) {
  try {
    run();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(MotionLaps, RejectsLapsOutOfRangeAndScenariosWithoutATurnAround) {
  for (const int laps : {0, -1, kMaxLaps + 1})
    EXPECT_NE(error_of([&] { bridge_laps(laps); }).find("motion.laps"), std::string::npos) << laps;
  for (const char* name : {"usv-corridor", "hauv-hull"}) {
    ScenarioOptions options;
    options.motion.laps = 2;
    EXPECT_NE(error_of([&] { make_scenario(name, 1, options); }).find("motion.laps"),
              std::string::npos)
        << name;
  }
  for (const char* text : {"motion.laps=0", "motion.laps=2.5", "motion.laps=1001"}) {
    SensorSettings sensors;
    ScenarioOptions options;
    EXPECT_NE(error_of([&] { apply_settings({text}, &sensors, &options); }).find("motion.laps"),
              std::string::npos)
        << text;
  }
  SensorSettings sensors;
  ScenarioOptions options;
  apply_settings({"motion.laps=6"}, &sensors, &options);
  EXPECT_EQ(options.motion.laps, 6);
}

}  // namespace
}  // namespace keel::sim
