// Repeated surveys (issue 16): a later survey of a scene carries the known changes its truth
// lists, measured here by casting rays at them, and nothing else of the scene moves.
#include <gtest/gtest.h>

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <set>

#include "tests/sim/scenarios.h"
#include "tests/sim/simulator.h"

namespace keel::sim {
namespace {

namespace fs = std::filesystem;

Scenario survey(const std::string& name, int k, uint64_t seed = 3) {
  ScenarioOptions options;
  options.survey = k;
  return make_scenario(name, seed, options);
}

// Range along -normal from 1 m in front of `center`.
double range_to(const Scenario& s, const Eigen::Vector3d& center, const Eigen::Vector3d& normal) {
  RayHit hit;
  EXPECT_TRUE(s.world->raycast(center + normal, -normal, 0.0, 5.0, &hit));
  return hit.range_m;
}

TEST(SurveyChanges, BridgeSpallsAreAsDeepAsTheTruthSays) {
  const Scenario first = survey("usv-bridge", 1), later = survey("usv-bridge", 2);
  EXPECT_TRUE(first.changes.empty());
  int spalls = 0, objects = 0;
  for (const SceneChange& c : later.changes) {
    ASSERT_NEAR(c.normal.norm(), 1.0, 1e-12);
    EXPECT_NEAR(range_to(first, c.center, c.normal), 1.0, 1e-9);  // on the first survey's face
    if (c.kind == "spall") {
      ++spalls;
      EXPECT_GE(c.depth_m, 0.03);
      EXPECT_LE(c.depth_m, 0.10);
      EXPECT_NEAR(range_to(later, c.center, c.normal), 1.0 + c.depth_m, 1e-9);
      // Just outside the footprint the face is where it was.
      const Eigen::Vector3d beside =
          c.center + Eigen::Vector3d(0, 0, 0.5 * c.footprint_height_m + 0.02);
      EXPECT_NEAR(range_to(later, beside, c.normal), 1.0, 1e-9);
      // The cavity's floor faces out of the pier.
      RayHit hit;
      ASSERT_TRUE(later.world->raycast(c.center + c.normal, -c.normal, 0.0, 5.0, &hit));
      EXPECT_GT(hit.normal.dot(c.normal), 0.999);
    } else {
      ASSERT_EQ(c.kind, "new_object");
      ++objects;
      EXPECT_NEAR(range_to(later, c.center, c.normal), 1.0 - c.height_m, 1e-9);
    }
  }
  EXPECT_EQ(spalls, 4);
  EXPECT_EQ(objects, 1);
  // Elsewhere the scene is the same.
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(-30, 18, 1), Eigen::Vector3d(0, -4.4, 3)}) {
    RayHit a, b;
    ASSERT_TRUE(first.world->raycast(Eigen::Vector3d(-30, 0, 1),
                                     (p - Eigen::Vector3d(-30, 0, 1)).normalized(), 0, 100, &a));
    ASSERT_TRUE(later.world->raycast(Eigen::Vector3d(-30, 0, 1),
                                     (p - Eigen::Vector3d(-30, 0, 1)).normalized(), 0, 100, &b));
    EXPECT_EQ(a.range_m, b.range_m);
  }
}

TEST(SurveyChanges, HullPatchesGrowOneIsNewTheCylinderIsGone) {
  ScenarioOptions options;
  options.fouling_patches = 3;
  const Scenario first = make_scenario("hauv-hull", 4, options);
  options.survey = 2;
  const Scenario later = make_scenario("hauv-hull", 4, options);
  int grown = 0, added = 0, removed = 0;
  for (const SceneChange& c : later.changes) {
    if (c.kind == "grown") {
      ++grown;
      const ForeignObject& before = first.foreign_objects.at(c.object);
      EXPECT_EQ(before.center, c.center);
      EXPECT_EQ(before.height_m, c.height_before_m);
      EXPECT_GE(c.height_m - c.height_before_m, 0.02);
      EXPECT_LE(c.height_m - c.height_before_m, 0.06);
      EXPECT_GT(c.radius_m, c.radius_before_m);
    } else if (c.kind == "new") {
      ++added;
      for (const ForeignObject& o : first.foreign_objects)
        EXPECT_GT((o.center - c.center).norm(), o.radius_m + c.radius_m);
    } else {
      ASSERT_EQ(c.kind, "removed");
      ++removed;
      EXPECT_EQ(first.foreign_objects.at(c.object).kind, ForeignObject::Kind::kCylinder);
    }
  }
  EXPECT_EQ(grown, 6);  // 3 fixed patches + 3 fouling patches
  EXPECT_EQ(added, 1);
  EXPECT_EQ(removed, 1);
  EXPECT_EQ(later.foreign_objects.size(), first.foreign_objects.size());  // -1 + 1
  EXPECT_TRUE(later.T_world_cad.isApprox(first.T_world_cad));
}

TEST(SurveyChanges, TruthFileListsTheChangesAndTheCorridorRefuses) {
  const fs::path out =
      fs::temp_directory_path() / ("keel_survey_changes_" + std::to_string(::getpid()));
  fs::remove_all(out);
  SimOptions options;
  options.scenario = "usv-bridge";
  options.seed = 2;
  options.survey = 2;
  options.duration_s = 2.0;
  options.sensors = {"imu", "lidar_h"};
  options.out_dir = out.string();
  run_simulation(options);
  const YAML::Node truth = YAML::LoadFile((out / "ground_truth" / "truth.yaml").string());
  EXPECT_EQ(truth["survey"].as<int>(), 2);
  ASSERT_TRUE(truth["changes"].IsSequence());
  EXPECT_EQ(truth["changes"].size(), 5u);
  EXPECT_EQ(truth["changes"][0]["kind"].as<std::string>(), "spall");
  EXPECT_GT(truth["changes"][0]["depth"].as<double>(), 0.0);
  const YAML::Node mission = YAML::LoadFile((out / "mission.yaml").string());
  EXPECT_EQ(mission["name"].as<std::string>(), "usv-bridge-seed2-survey2");
  fs::remove_all(out);

  options.scenario = "usv-corridor";
  EXPECT_THROW(run_simulation(options), std::invalid_argument);
  EXPECT_EQ(survey_seed(9, 1), 9u);
  EXPECT_NE(survey_seed(9, 2), 9u);
}

}  // namespace
}  // namespace keel::sim
