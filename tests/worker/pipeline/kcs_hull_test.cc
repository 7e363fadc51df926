// Issue 18: the hull stages on a real CAD hull. keel-sim surveys the KRISO container ship
// (../shared/data/KCS.stl, 230 m, open at the deck) with its foreign objects, and `ba`
// (mode proposed, the SIFT frontend) then `inspect` must find every object at least 5 cm
// high, measure the 0.11 m cylinder within 1.5 cm, and report no shape where the hull is
// clean (issue 6's hull targets). Skipped, saying so, without ../shared/data.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>

#include "tests/sim/simulator.h"
#include "tests/worker/pipeline/stage_run.h"
#include "worker/stages/ba/stage.h"
#include "worker/stages/inspect/stage.h"

namespace keel::pipeline {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

fs::path kcs_stl() { return fs::path(KEEL_SHARED_DIR) / "data" / "KCS.stl"; }

TEST(KcsHull, BaAndInspectFindEveryObjectAndNoFalseShape) {
  if (!fs::exists(kcs_stl())) GTEST_SKIP() << kcs_stl() << " absent (shared/data/KCS.stl)";
  const fs::path root = fs::temp_directory_path() / ("keel_kcs_hull_" + std::to_string(::getpid()));
  fs::remove_all(root);
  sim::SimOptions sim;
  sim.scenario = "hauv-hull";
  sim.seed = 1;
  sim.out_dir = (root / "mission").string();
  sim.settings = {"hull.cad=" + kcs_stl().string()};
  sim::run_simulation(sim);

  const auto ba = make_ba_stage();
  const json ba_report =
      testing::run_stage(*ba, root / "mission", {{"mode", "proposed"}}, root / "work").result.report;
  const json& proposed = ba_report["modes"]["proposed"];
  // Fig. 18: the model-assisted BA brings the DVL ranges onto the CAD hull.
  EXPECT_LT(proposed["dvl_residuals_final"]["robust_sigma_m"].get<double>(),
            proposed["dvl_residuals_gicp"]["robust_sigma_m"].get<double>() / 3.0);

  const auto inspect = make_inspect_stage();
  const json report =
      testing::run_stage(*inspect, root / "mission", json::object(), root / "work").result.report;
  const json& truth = report["truth"];
  ASSERT_TRUE(truth.is_object()) << "the simulated mission's truth.yaml lists the objects";
  int objects = 0;
  for (const json& object : truth["objects"]) {
    const double height = object["true_height_m"].get<double>();
    if (height < 0.05) continue;
    ++objects;
    EXPECT_TRUE(object["found"].get<bool>()) << object.dump();
    if (object["kind"] == "cylinder" && object["found"].get<bool>())
      EXPECT_LE(std::abs(object["height_error_m"].get<double>()), 0.015) << object.dump();
  }
  EXPECT_GE(objects, 3);
  EXPECT_EQ(truth["false_shapes"].get<int>(), 0) << report["shapes"].dump();
  fs::remove_all(root);
}

}  // namespace
}  // namespace keel::pipeline
