// Stage `refine` with GNSS on keel-sim's USV scenarios (issue 30): every fix keel-sim reflected
// off the piers is rejected by the gate, no-fix messages are counted, and the refined keyframes,
// unaligned (the world frame is the ENU frame the fixes place them in), are within 1.5 x the
// simulated GNSS sigma of the truth on open water, where without GNSS they drift by metres.
// MAP anchors are off here: with them the recorded MAP poses (keel-sim writes them in the true
// world frame, 0.2 m off) already pin the trajectory, and GNSS would have little to show.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include "tests/sim/simulator.h"
#include "tests/worker/pipeline/stage_run.h"
#include "worker/io/tum.h"
#include "worker/stages/refine/artifacts.h"
#include "worker/stages/refine/stage.h"

namespace keel::pipeline {
namespace {

namespace fs = std::filesystem;

constexpr double kSigmaM = 0.5;  // keel-sim's horizontal GNSS sigma (GnssOptions)

fs::path temp_root() {
  return fs::temp_directory_path() / ("keel_refine_gnss_" + std::to_string(::getpid()));
}

fs::path simulated(const std::string& scenario, uint64_t seed, double duration_s) {
  const fs::path dir = temp_root() / (scenario + std::to_string(seed));
  sim::SimOptions o;
  o.scenario = scenario;
  o.seed = seed;
  o.out_dir = dir.string();
  o.duration_s = duration_s;
  o.sensors = {"imu", "dvl"};
  o.gnss = true;
  sim::run_simulation(o);
  return dir;
}

struct TruthFix {
  TimeNs t_ns;
  int kind;  // 0 clean, 1 multipath, 2 no fix
};

std::vector<TruthFix> truth_fixes(const fs::path& mission) {
  std::ifstream in(mission / "ground_truth" / "gnss.csv");
  std::string line;
  std::getline(in, line);
  std::vector<TruthFix> out;
  while (std::getline(in, line)) {
    double t, e, n, u, kind;
    if (std::sscanf(line.c_str(), "%lf,%lf,%lf,%lf,%lf", &t, &e, &n, &u, &kind) == 5)
      out.push_back({static_cast<TimeNs>(std::llround(t * 1e3)) * 1000000, static_cast<int>(kind)});
  }
  return out;
}

// Unaligned RMS position error of the keyframes whose true position passes `keep`.
template <typename Keep>
double unaligned_ate_m(const Trajectory& truth, const Trajectory& estimate, Keep keep) {
  double sum = 0.0;
  size_t n = 0, j = 0;
  for (const StampedPose& p : estimate) {
    while (j + 1 < truth.size() && truth[j + 1].t_ns <= p.t_ns) ++j;
    if (std::llabs(truth[j].t_ns - p.t_ns) > 10000000) continue;
    const Eigen::Vector3d t = truth[j].T_world_body.translation();
    if (!keep(t)) continue;
    sum += (p.T_world_body.translation() - t).squaredNorm();
    ++n;
  }
  EXPECT_GT(n, 10u);
  return std::sqrt(sum / static_cast<double>(n));
}

nlohmann::json refine(const fs::path& mission, const std::string& name, bool gnss) {
  const nlohmann::json options = {{"map_anchors", false}, {"gnss", gnss}};
  return testing::run_stage(*make_refine_stage(), mission, options, temp_root() / name)
      .result.report;
}

class RefineGnssTest : public ::testing::Test {
 protected:
  static void TearDownTestSuite() { fs::remove_all(temp_root()); }
};

TEST_F(RefineGnssTest, BridgeMultipathIsRejectedAndOpenWaterMeetsTheGnssNoise) {
  const fs::path mission = simulated("usv-bridge", 2, 150.0);
  const nlohmann::json r = refine(mission, "bridge", true);
  const nlohmann::json& g = r.at("gnss");
  std::set<long long> rejected_ms;
  for (double t : g.at("rejected_t_s")) rejected_ms.insert(std::llround(t * 1e3));
  size_t multipath = 0, clean = 0, no_fix = 0, clean_rejected = 0;
  for (const TruthFix& f : truth_fixes(mission)) {
    const bool rejected = rejected_ms.count(f.t_ns / 1000000) > 0;
    if (f.kind == 1) {
      ++multipath;
      EXPECT_TRUE(rejected) << "multipath fix at " << f.t_ns << " was used";
    } else if (f.kind == 0) {
      ++clean;
      clean_rejected += rejected;
    } else {
      ++no_fix;
    }
  }
  ASSERT_GT(multipath, 20u);
  EXPECT_EQ(g.at("no_fix").get<size_t>(), no_fix);
  // The gate is chi-square at p = 0.999 with 3 dof: a clean fix is rejected about 1 in 1000,
  // plus those the estimate near the bridge (without fixes under the deck) is off for.
  EXPECT_LE(clean_rejected, clean / 50 + 1) << clean_rejected << " of " << clean;
  EXPECT_EQ(g.at("rejected").get<size_t>(), multipath + clean_rejected);
  EXPECT_EQ(r.at("origin").at("frame"), "ENU");

  const Trajectory truth = io::read_tum(mission / "ground_truth" / "trajectory.tum");
  const auto open_water = [](const Eigen::Vector3d& p) {
    const bool under_deck = std::abs(p.x()) <= 3.5 && std::abs(p.y()) <= 21.0;
    const double to_pier = std::min(std::hypot(p.x(), p.y() - 7), std::hypot(p.x(), p.y() + 7));
    return !under_deck && to_pier > 12.0;
  };
  const double with = unaligned_ate_m(
      truth, io::read_tum(temp_root() / "bridge" / kRefinedTrajectoryFile), open_water);
  EXPECT_LE(with, 1.5 * kSigmaM);
  refine(mission, "bridge_without", false);
  const double without = unaligned_ate_m(
      truth, io::read_tum(temp_root() / "bridge_without" / kRefinedTrajectoryFile), open_water);
  EXPECT_LT(with, without);
  std::printf(
      "usv-bridge seed 2 (150 s), open water: unaligned ATE %.3f m with GNSS, %.3f m "
      "without; %zu multipath fixes, %zu rejected clean of %zu\n",
      with, without, multipath, clean_rejected, clean);
}

TEST_F(RefineGnssTest, CorridorMeetsTheGnssNoiseWhereItDriftsWithout) {
  const fs::path mission = simulated("usv-corridor", 2, 0.0);
  refine(mission, "corridor", true);
  refine(mission, "corridor_without", false);
  const Trajectory truth = io::read_tum(mission / "ground_truth" / "trajectory.tum");
  const auto all = [](const Eigen::Vector3d&) { return true; };
  const double with =
      unaligned_ate_m(truth, io::read_tum(temp_root() / "corridor" / kRefinedTrajectoryFile), all);
  const double without = unaligned_ate_m(
      truth, io::read_tum(temp_root() / "corridor_without" / kRefinedTrajectoryFile), all);
  EXPECT_LE(with, 1.5 * kSigmaM);
  EXPECT_LT(with, without);
  std::printf("usv-corridor seed 2: unaligned ATE %.3f m with GNSS, %.3f m without\n", with,
              without);
}

}  // namespace
}  // namespace keel::pipeline
