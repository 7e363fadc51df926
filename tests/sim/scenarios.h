// The three scenarios of issue 3: usv-bridge (seed 000 Environment 1), usv-corridor
// (Environment 2) and hauv-hull (seed 001's hull survey with a servo-driven sensor tray).
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/geodesy.h"
#include "core/pose.h"
#include "tests/sim/analytic_scene.h"
#include "tests/sim/cad_hull.h"
#include "tests/sim/camera_sim.h"
#include "tests/sim/gnss_sim.h"
#include "tests/sim/hull_model.h"
#include "tests/sim/hull_world.h"
#include "tests/sim/motion.h"

namespace keel::sim {

// hauv-hull: hull.fouling_patches. With 0.3 m between objects the surveyed band holds about
// 90-100 patches; 90 were placed on every seed of 1-100, so 60 leaves a margin.
constexpr int kMaxFoulingPatches = 60;

// A known change of a repeated survey (survey >= 2) against the first, listed in truth.yaml's
// `changes`. Frames: world (the scene's, which every survey shares).
struct SceneChange {
  // usv-bridge: "spall" (material removed from a pier face), "new_object" (a box attached to
  // a pier face); hauv-hull: "grown" (a fouling patch higher and wider), "new", "removed".
  std::string kind;
  std::string structure;                             // the pier's name, or "hull"
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  // on the first survey's surface
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // outward unit normal there
  // Rectangular footprints on a pier face: width along the face (horizontal), height up it.
  double width_m = 0.0, footprint_height_m = 0.0;
  double depth_m = 0.0;   // spall: how deep the material was removed
  double height_m = 0.0;  // how far the object stands out now (removed: stood out before)
  double height_before_m = 0.0, radius_m = 0.0, radius_before_m = 0.0;  // hull patches
  int object = -1;  // hauv-hull: index into the first survey's foreign_objects
};

struct ScenarioOptions {
  MotionOptions motion;  // the scenario sets speed/heading defaults, overrides follow
  bool speed_overridden = false;
  HullOptions hull;
  CadHullOptions cad;            // hauv-hull on a user's CAD mesh instead of `hull` (hull.cad=FILE)
  double hull_standoff_m = 1.5;  // seed 001: 1-2 m
  double landmark_density_per_m2 = 40.0;
  // hauv-hull: biofouling patches scattered over the surveyed hull besides the four fixed
  // objects (same sizes as the fixed patches). 0 keeps the clean hull of the default mission;
  // the paper's hulls had 18 % and 66 % of their features off the model (lambda = 1 fractions
  // 0.82 and 0.34), the clean keel-sim hull about 0.3 %.
  int fouling_patches = 0;
  // 1: the scene as first surveyed; 2, 3, ...: the same scene surveyed again later, with the
  // known changes of Scenario::changes and its own vehicle motion and sensor noise.
  int survey = 1;
};

// Seed of a survey's motion and sensor noise: the scene's seed for the first survey.
uint64_t survey_seed(uint64_t seed, int survey);

struct Scenario {
  std::string name;
  std::string platform;  // usv | hauv
  std::unique_ptr<PathMotion> motion;
  std::unique_ptr<SimWorld> world;
  const AnalyticScene* analytic = nullptr;  // usv scenarios
  const HullWorld* hull_world = nullptr;    // hauv-hull
  double default_duration_s = 0.0;
  std::vector<std::string> default_sensors;  // --sensors names
  // Sensors the scenario has but writes only when asked (--sensors, --gnss): gnss on USVs, so
  // that missions written without it stay what they were.
  std::vector<std::string> optional_sensors;
  // Where the world frame is on the earth (its local ENU origin; usv scenarios) and what hides
  // or reflects GNSS signals there.
  GeodeticPoint origin;
  GnssEnvironment gnss_environment;
  std::map<std::string, Pose3> T_body_sensor;  // at servo angle 0 for tray sensors
  std::vector<std::string> tray_sensors;       // sensors riding the servo tray
  Eigen::Vector3d degenerate_axis_world = Eigen::Vector3d::Zero();
  CameraModel camera;
  double camera_rate_hz = 2.0;
  // Servo tray (hauv-hull).
  bool has_servo = false;
  Pose3 T_body_servo = Pose3::Identity();
  Eigen::Vector3d servo_axis = Eigen::Vector3d::UnitY();  // in the servo frame
  // Hull truth (hauv-hull).
  HullOptions hull_options;  // the procedural hull's, unused with a CAD hull
  TriangleMesh cad_mesh;     // CAD frame
  Pose3 T_world_cad = Pose3::Identity();
  std::vector<ForeignObject> foreign_objects;
  TriangleMesh real_mesh_world;  // CAD at T_world_cad plus the objects
  // Repeated surveys.
  int survey = 1;
  std::vector<SceneChange> changes;

  double servo_angle(double t_s) const;
  // Extrinsic at time t (tray sensors follow the servo angle).
  Pose3 T_body_sensor_at(const std::string& sensor, double t_s) const;
};

// Throws std::invalid_argument for an unknown name.
Scenario make_scenario(const std::string& name, uint64_t seed, const ScenarioOptions& options = {});
std::vector<std::string> scenario_names();

}  // namespace keel::sim
