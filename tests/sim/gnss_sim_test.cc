// keel-sim's GNSS: noise statistics against the stated sigmas, dropouts exactly under the
// deck, multipath only near the reflectors with the stated bias, and a mission with gnss whose
// other files are byte for byte those of the same seed without it.
#include "tests/sim/gnss_sim.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "core/geodesy.h"
#include "tests/sim/scenarios.h"
#include "tests/sim/simulator.h"
#include "worker/io/gnss_csv.h"

namespace keel::sim {
namespace {
namespace fs = std::filesystem;

TEST(GnssSim, OpenWaterNoiseHasTheStatedSigmas) {
  const Scenario s = make_scenario("usv-corridor", 3);
  GnssOptions options;
  options.rate_hz = 100.0;  // 3800 fixes over the corridor
  const Eigen::Vector3d lever(-0.5, 0.0, 2.0);
  const auto fixes = simulate_gnss(*s.motion, s.default_duration_s, lever, {}, options, 3);
  ASSERT_GT(fixes.size(), 3000u);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero(), sum2 = Eigen::Vector3d::Zero();
  for (const auto& f : fixes) {
    ASSERT_EQ(f.kind, GnssFixKind::kClean);
    const KinematicState k = s.motion->state(f.t_ns * 1e-9);
    EXPECT_LT((f.antenna_true_world - (k.p_world + k.q_world_body * lever)).norm(), 1e-9);
    const Eigen::Vector3d e = f.antenna_measured_world - f.antenna_true_world;
    sum += e;
    sum2 += e.cwiseProduct(e);
  }
  const double n = static_cast<double>(fixes.size());
  const Eigen::Vector3d sigma = (sum2 / n).cwiseSqrt();
  // The sample sigma of n Gaussian draws has a relative spread of 1 / sqrt(2 n) (1.1 % here):
  // 5 % is over 4 of them.
  EXPECT_NEAR(sigma.x(), options.horizontal_sigma_m, 0.05 * options.horizontal_sigma_m);
  EXPECT_NEAR(sigma.y(), options.horizontal_sigma_m, 0.05 * options.horizontal_sigma_m);
  EXPECT_NEAR(sigma.z(), options.vertical_sigma_m, 0.05 * options.vertical_sigma_m);
  EXPECT_LT((sum / n).head<2>().norm(), 4.0 * options.horizontal_sigma_m / std::sqrt(n));
}

TEST(GnssSim, NoFixUnderTheDeckMultipathOnlyNearThePiers) {
  const Scenario s = make_scenario("usv-bridge", 1);
  GnssOptions options;
  options.rate_hz = 10.0;
  const auto fixes = simulate_gnss(*s.motion, s.default_duration_s, {-0.5, 0.0, 2.0},
                                   s.gnss_environment, options, 1);
  size_t no_fix = 0, multipath = 0, near_clean = 0;
  for (const auto& f : fixes) {
    const Eigen::Vector2d xy = f.antenna_true_world.head<2>();
    const bool under = std::abs(xy.x()) <= 3.5 && std::abs(xy.y()) <= 21.0;
    EXPECT_EQ(f.kind == GnssFixKind::kNoFix, under) << xy.transpose();
    no_fix += under;
    if (under) {
      EXPECT_TRUE(std::isnan(f.antenna_measured_world.x()));
      continue;
    }
    const Eigen::Vector2d pier = xy.y() > 0 ? Eigen::Vector2d(0, 7) : Eigen::Vector2d(0, -7);
    const double distance = (xy - pier).norm();
    if (f.kind == GnssFixKind::kMultipath) {
      ++multipath;
      EXPECT_LT(distance, options.multipath_radius_m);
      const Eigen::Vector2d e = f.antenna_measured_world.head<2>() - xy;
      // Bias in [3, 8] m away from the pier, plus 0.5 m noise per axis (5 sigma margin).
      EXPECT_GT(e.norm(), options.multipath_bias_min_m - 2.5 * options.horizontal_sigma_m * 2);
      EXPECT_LT(e.norm(), options.multipath_bias_max_m + 2.5 * options.horizontal_sigma_m * 2);
      EXPECT_GT(e.normalized().dot((xy - pier).normalized()), 0.5);
    } else if (distance < options.multipath_radius_m) {
      ++near_clean;
    }
  }
  EXPECT_GT(no_fix, 50u);
  EXPECT_GT(multipath, 50u);
  // About half of the fixes near the piers are reflected (probability 0.5).
  const double share = static_cast<double>(multipath) / static_cast<double>(multipath + near_clean);
  EXPECT_NEAR(share, options.multipath_probability, 0.1);
}

std::string slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

TEST(GnssSim, MissionWithGnssKeepsTheOtherFilesAndItsFixesAreTheTruthPlusNoise) {
  const fs::path root = fs::temp_directory_path() / ("keel_gnss_sim_" + std::to_string(::getpid()));
  SimOptions o;
  o.scenario = "usv-corridor";
  o.seed = 4;
  o.duration_s = 20.0;
  o.sensors = {"imu", "dvl", "depth"};
  o.out_dir = (root / "plain").string();
  run_simulation(o);
  o.gnss = true;
  o.out_dir = (root / "gnss").string();
  const SimSummary summary = run_simulation(o);
  EXPECT_EQ(summary.gnss_fixes, 41u);  // 2 Hz over [0, 20] s
  for (const auto& entry : fs::recursive_directory_iterator(root / "plain")) {
    if (!entry.is_regular_file()) continue;
    const fs::path rel = fs::relative(entry.path(), root / "plain");
    if (rel == "mission.yaml" || rel == fs::path("ground_truth") / "truth.yaml") continue;
    EXPECT_EQ(slurp(entry.path()), slurp(root / "gnss" / rel)) << rel;
  }
  const io::GnssSeries fixes = io::read_gnss_csv(root / "gnss" / "gnss.csv");
  ASSERT_EQ(fixes.size(), 41u);
  const Scenario s = make_scenario("usv-corridor", 4);
  const LocalEnuFrame enu(s.origin);
  std::ifstream truth(root / "gnss" / "ground_truth" / "gnss.csv");
  std::string line;
  std::getline(truth, line);
  for (const auto& f : fixes) {
    ASSERT_TRUE(std::getline(truth, line));
    double t, e, n, u, kind;
    ASSERT_EQ(std::sscanf(line.c_str(), "%lf,%lf,%lf,%lf,%lf", &t, &e, &n, &u, &kind), 5);
    EXPECT_EQ(kind, 0.0);
    const Eigen::Vector3d p =
        enu.to_enu({f.latitude_deg, f.longitude_deg, f.height_m}) - Eigen::Vector3d(e, n, u);
    EXPECT_LT(p.head<2>().norm(), 5 * 0.5);  // 5 sigma
    EXPECT_LT(std::abs(p.z()), 5 * 1.0);
  }
  fs::remove_all(root);
}

}  // namespace
}  // namespace keel::sim
