// Algorithm 1, seed 000: hand-computed interpolation, the gap rule, dropouts, bad input.
#include "worker/slam/dvl_imu_reconciliation.h"

#include <gtest/gtest.h>

#include <stdexcept>

namespace keel::slam {
namespace {

constexpr TimeNs kMs = 1'000'000;

std::vector<ImuSample> imu_every_10ms(int n) {
  std::vector<ImuSample> imu;
  for (int k = 0; k < n; ++k) {
    ImuSample s;
    s.t_ns = k * 10 * kMs;
    s.gyro_radps = Eigen::Vector3d(0.01 * k, 0, 0);
    imu.push_back(s);
  }
  return imu;
}

DvlSample dvl(TimeNs t_ns, double vx, double vy, bool valid = true) {
  DvlSample d;
  d.t_ns = t_ns;
  d.velocity_mps = Eigen::Vector3d(vx, vy, 0.0);
  d.valid = valid;
  return d;
}

TEST(Algorithm1, InterpolatesAtImuTimesAndRotatesIntoTheImuFrame) {
  const auto imu = imu_every_10ms(13);  // 0 .. 120 ms
  const std::vector<DvlSample> d = {dvl(0, 1, 0), dvl(50 * kMs, 2, 0), dvl(100 * kMs, 4, 2)};
  Eigen::Matrix3d Rz90;
  Rz90 << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  const auto p = reconcile_dvl_imu(d, imu, Rz90);
  // IMU 0..100 ms lie inside [0, 100] ms; 110 and 120 ms lie after the last DVL sample.
  ASSERT_EQ(p.size(), 11u);
  // Hand-computed: v(t) = 1 + t/50 on [0, 50] ms; (2, 0) + (t-50)/50 * (2, 2) on [50, 100].
  const double expected_vx[] = {1.0, 1.2, 1.4, 1.6, 1.8, 2.0, 2.4, 2.8, 3.2, 3.6, 4.0};
  const double expected_vy[] = {0, 0, 0, 0, 0, 0, 0.4, 0.8, 1.2, 1.6, 2.0};
  for (size_t k = 0; k < p.size(); ++k) {
    EXPECT_EQ(p[k].t_ns, imu[k].t_ns);
    EXPECT_NEAR(p[k].velocity_dvl_mps.x(), expected_vx[k], 1e-12) << k;
    EXPECT_NEAR(p[k].velocity_dvl_mps.y(), expected_vy[k], 1e-12) << k;
    // Rz(90 deg) (vx, vy) = (-vy, vx).
    EXPECT_NEAR(p[k].velocity_imu_mps.x(), -expected_vy[k], 1e-12) << k;
    EXPECT_NEAR(p[k].velocity_imu_mps.y(), expected_vx[k], 1e-12) << k;
    EXPECT_EQ(p[k].gyro_radps, imu[k].gyro_radps);
    EXPECT_NEAR(p[k].dvl_period_s, 0.05, 1e-12);
  }
}

TEST(Algorithm1, DoesNotBridgeGapsLongerThanTheThreshold) {
  const auto imu = imu_every_10ms(101);  // 0 .. 1 s
  const std::vector<DvlSample> d = {dvl(0, 1, 0), dvl(50 * kMs, 1, 0), dvl(800 * kMs, 3, 0),
                                    dvl(850 * kMs, 3, 0)};
  ReconcileOptions strict;
  strict.max_dvl_gap_s = 0.5;  // the 750 ms gap is longer
  const auto p = reconcile_dvl_imu(d, imu, Eigen::Matrix3d::Identity(), strict);
  // 0..50 ms (6 samples) and 800..850 ms (6 samples); nothing in between.
  ASSERT_EQ(p.size(), 12u);
  for (const PseudoSample& s : p) {
    EXPECT_TRUE(s.t_ns <= 50 * kMs || s.t_ns >= 800 * kMs) << s.t_ns;
  }
  ReconcileOptions lax;
  lax.max_dvl_gap_s = 1.0;
  const auto q = reconcile_dvl_imu(d, imu, Eigen::Matrix3d::Identity(), lax);
  ASSERT_EQ(q.size(), 86u);  // 0 .. 850 ms
  // Bridged: at 420 ms, interpolated between the samples at 50 and 800 ms.
  const PseudoSample& mid = q[42];
  ASSERT_EQ(mid.t_ns, 420 * kMs);
  EXPECT_NEAR(mid.velocity_dvl_mps.x(), 1.0 + 2.0 * (420.0 - 50.0) / 750.0, 1e-12);
}

TEST(Algorithm1, SkipsInvalidSamples) {
  const auto imu = imu_every_10ms(11);
  const std::vector<DvlSample> d = {dvl(0, 1, 0), dvl(50 * kMs, 99, 99, /*valid=*/false),
                                    dvl(100 * kMs, 3, 0)};
  const auto p = reconcile_dvl_imu(d, imu, Eigen::Matrix3d::Identity());
  ASSERT_EQ(p.size(), 11u);
  EXPECT_NEAR(p[5].velocity_dvl_mps.x(), 2.0, 1e-12);  // 1 + (3 - 1) * 50 / 100
  EXPECT_NEAR(p[5].dvl_period_s, 0.1, 1e-12);
}

TEST(Algorithm1, RejectsUnsortedStampsNamingTheSample) {
  auto imu = imu_every_10ms(5);
  std::swap(imu[2].t_ns, imu[3].t_ns);
  const std::vector<DvlSample> d = {dvl(0, 1, 0), dvl(50 * kMs, 1, 0)};
  try {
    reconcile_dvl_imu(d, imu, Eigen::Matrix3d::Identity());
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("imu sample 3"), std::string::npos) << e.what();
  }
  std::vector<DvlSample> bad = {dvl(0, 1, 0), dvl(0, 1, 0)};
  EXPECT_THROW(reconcile_dvl_imu(bad, imu_every_10ms(5), Eigen::Matrix3d::Identity()),
               std::invalid_argument);
}

TEST(HoldSegments, TileTheIntervalWithClippedPieces) {
  struct S {
    TimeNs t_ns;
    int id;
  };
  const std::vector<S> s = {{0, 0}, {10, 1}, {20, 2}, {30, 3}};
  std::vector<std::pair<int, double>> pieces;
  ASSERT_TRUE(for_each_hold_segment(s, 5, 25, 100,
                                    [&](const S& m, double dt) { pieces.emplace_back(m.id, dt); }));
  ASSERT_EQ(pieces.size(), 3u);
  EXPECT_EQ(pieces[0].first, 0);
  EXPECT_DOUBLE_EQ(pieces[0].second, 5e-9);
  EXPECT_EQ(pieces[1].first, 1);
  EXPECT_DOUBLE_EQ(pieces[1].second, 10e-9);
  EXPECT_EQ(pieces[2].first, 2);
  EXPECT_DOUBLE_EQ(pieces[2].second, 5e-9);
  EXPECT_FALSE(for_each_hold_segment(s, 5, 35, 100, [](const S&, double) {}));  // not covered
  EXPECT_FALSE(for_each_hold_segment(s, 5, 25, 9, [](const S&, double) {}));    // gap > 9 ns
}

}  // namespace
}  // namespace keel::slam
