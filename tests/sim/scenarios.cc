#include "tests/sim/scenarios.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <stdexcept>

#include "tests/sim/cad_hull.h"
#include "tests/sim/mesh_bvh.h"
#include "tests/sim/rng.h"

namespace keel::sim {
namespace {

Pose3 pose(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  Pose3 T = Pose3::Identity();
  T.linear() = R;
  T.translation() = t;
  return T;
}

Eigen::Matrix3d rot_x(double a) {
  return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitX()).toRotationMatrix();
}
Eigen::Matrix3d rot_y(double a) {
  return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitY()).toRotationMatrix();
}
Eigen::Matrix3d rot_z(double a) {
  return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

// Camera looking along body +x: camera x = body -y, camera y = body -z, camera z = body x.
Eigen::Matrix3d forward_looking() {
  Eigen::Matrix3d R;
  R.col(0) = -Eigen::Vector3d::UnitY();
  R.col(1) = -Eigen::Vector3d::UnitZ();
  R.col(2) = Eigen::Vector3d::UnitX();
  return R;
}

const Material kWater{0.12, false, Texture::kWater};
const Material kSeabed{0.3, true, Texture::kSeabed};
const Material kConcrete{0.55, true, Texture::kConcrete};
const Material kCinder{0.5, true, Texture::kCinder};
const Material kWhiteWall{0.85, true, Texture::kPlain};

void add_water(AnalyticScene* scene) {
  scene->add(make_plane({0, 0, 0}, {0, 0, 1}, kWater, "water"));
  scene->add(make_plane({0, 0, -6}, {0, 0, 1}, kSeabed, "seabed"));
}

// Pier geometry (pier-local x across the flat faces, y along the pier).
constexpr double kPierHalfLength = 2.5, kPierRadius = 1.2, kPierZ0 = -6.0, kPierZ1 = 6.0;

void add_stadium_pier(AnalyticScene* scene, const Eigen::Vector3d& center, const std::string& name,
                      const std::vector<SceneChange>& changes) {
  // Rounded-end concrete pier from the seabed to the deck (Welland Canal Bridge 13 style).
  const double half_length = kPierHalfLength, radius = kPierRadius, z0 = kPierZ0, z1 = kPierZ1;
  const Eigen::Vector3d c(center.x(), center.y(), 0.5 * (z0 + z1));
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  // Spalls of a later survey: cavities opening through the flat faces x = +-radius.
  std::vector<Eigen::AlignedBox3d> cavities;
  for (const SceneChange& change : changes) {
    if (change.structure != name || change.kind != "spall") continue;
    const Eigen::Vector3d at = change.center - c;  // on the face, box-local (axes = world)
    const double side = change.normal.x() > 0 ? 1.0 : -1.0;
    const Eigen::Vector3d half_size(0.0, 0.5 * change.width_m, 0.5 * change.footprint_height_m);
    Eigen::Vector3d lo = at - half_size, hi = at + half_size;
    // From depth_m inside the face to 5 cm outside it (the mouth).
    lo.x() = side > 0 ? radius - change.depth_m : -radius - 0.05;
    hi.x() = side > 0 ? radius + 0.05 : -radius + change.depth_m;
    cavities.emplace_back(lo, hi);
  }
  scene->add(make_box_with_cavities(c, I, {radius, half_length, 0.5 * (z1 - z0)}, cavities,
                                    kConcrete, name));
  for (const SceneChange& change : changes) {
    if (change.structure != name || change.kind != "new_object") continue;
    // A box (a junction box, a bracket) standing height_m out of the face.
    const Eigen::Vector3d box_center = change.center + 0.5 * change.height_m * change.normal;
    scene->add(
        make_box(box_center, I,
                 {0.5 * change.height_m, 0.5 * change.width_m, 0.5 * change.footprint_height_m},
                 kConcrete, name + "_attachment"));
  }
  scene->add(make_cylinder(c + Eigen::Vector3d(0, half_length, 0), I, radius, 0.5 * (z1 - z0),
                           kConcrete, name + "_north"));
  scene->add(make_cylinder(c - Eigen::Vector3d(0, half_length, 0), I, radius, 0.5 * (z1 - z0),
                           kConcrete, name + "_south"));
}

// The changes of a later survey of the bridge: a spall on each flat face of both piers, 3 to
// 10 cm deep, and a box attached to the north pier's east face, above the water where the
// lidars see them. Sizes and places are jittered by the scene seed, the same for every later
// survey of that seed.
std::vector<SceneChange> bridge_changes(uint64_t seed) {
  Rng rng(seed, Stream::kScene, 16);
  const double depths[] = {0.03, 0.05, 0.07, 0.10};
  struct Face {
    const char* pier;
    double pier_y, side;
  };
  const Face faces[] = {{"pier_north", 7.0, 1.0},
                        {"pier_north", 7.0, -1.0},
                        {"pier_south", -7.0, 1.0},
                        {"pier_south", -7.0, -1.0}};
  std::vector<SceneChange> out;
  for (int k = 0; k < 4; ++k) {
    SceneChange spall;
    spall.kind = "spall";
    spall.structure = faces[k].pier;
    spall.width_m = rng.uniform(0.4, 0.7);
    spall.footprint_height_m = rng.uniform(0.3, 0.5);
    spall.depth_m = depths[k];
    // The north pier's east face also holds the new object: the spall keeps to y < 0 there.
    const double y = k == 0 ? rng.uniform(-1.4, -0.7) : rng.uniform(-1.0, 1.0);
    spall.center = {faces[k].side * kPierRadius, faces[k].pier_y + y, rng.uniform(0.8, 2.2)};
    spall.normal = {faces[k].side, 0.0, 0.0};
    out.push_back(spall);
  }
  SceneChange box;
  box.kind = "new_object";
  box.structure = "pier_north";
  box.width_m = rng.uniform(0.4, 0.6);
  box.footprint_height_m = rng.uniform(0.5, 0.7);
  box.height_m = rng.uniform(0.15, 0.25);
  box.center = {kPierRadius, 7.0 + rng.uniform(0.7, 1.4), rng.uniform(1.0, 2.0)};
  box.normal = {1.0, 0.0, 0.0};
  out.push_back(box);
  return out;
}

std::unique_ptr<AnalyticScene> bridge_scene(const std::vector<SceneChange>& changes) {
  auto scene = std::make_unique<AnalyticScene>();
  add_water(scene.get());
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  // Partially submerged cinder-block walls along both banks (seed 000 Fig. 3(a)).
  ReliefWallGeometry north;
  north.center = {0, 20, 0}, north.yaw_rad = M_PI, north.length_m = 200, north.z_min = -6,
  north.z_max = 2.5;
  scene->add(make_relief_wall(north, kCinder, "north_wall"));
  ReliefWallGeometry south = north;
  south.center = {0, -20, 0}, south.yaw_rad = 0.0;
  scene->add(make_relief_wall(south, kCinder, "south_wall"));
  // Pilasters at irregular spacing break the walls' translational symmetry.
  const double north_x[] = {-52, -37, -21, -12, 9, 23, 41, 55};
  const double south_x[] = {-58, -44, -29, -14, 14, 31, 38, 52};
  for (double x : north_x)
    scene->add(make_box({x, 19.6, -1.75}, I, {0.35, 0.4, 4.25}, kConcrete, "pilaster"));
  for (double x : south_x)
    scene->add(make_box({x, -19.6, -1.75}, I, {0.35, 0.4, 4.25}, kConcrete, "pilaster"));
  // The bridge: two piers, deck and girders.
  add_stadium_pier(scene.get(), {0, 7, 0}, "pier_north", changes);
  add_stadium_pier(scene.get(), {0, -7, 0}, "pier_south", changes);
  scene->add(make_box({0, 0, 6.75}, I, {3.5, 21.0, 0.75}, kConcrete, "deck"));
  scene->add(make_box({2.6, 0, 5.75}, I, {0.2, 21.0, 0.25}, kConcrete, "girder_east"));
  scene->add(make_box({-2.6, 0, 5.75}, I, {0.2, 21.0, 0.25}, kConcrete, "girder_west"));
  // Mooring dolphins (timber piles).
  const Eigen::Vector3d piles[] = {
      {-27, 11, -1.5}, {-18, -12, -1.5}, {19, -13, -1.5}, {33, 10, -1.5}};
  for (const auto& p : piles) scene->add(make_cylinder(p, I, 0.35, 5.5, kConcrete, "pile"));
  return scene;
}

std::vector<Eigen::Vector3d> bridge_waypoints() {
  // Approach along the channel, figure-eight around both piers (loop closures), back along
  // the south wall to the start. Scaled so the path is ~265 m (seed 000 Sec. V-C).
  const double xy[][2] = {{-90, 1.5},   {-78, 1.5},   {-66, 1.5},    {-54, 1.5},   {-42, 1.5},
                          {-30, 1.2},   {-20, 0.8},   {-11, 0.3},    {-5, 0.0},    {0, 0.0},
                          {5.5, 1.5},   {9.5, 6.5},   {7.5, 13.0},   {0, 16.5},    {-7.5, 13.0},
                          {-9.5, 7.0},  {-5.5, 1.5},  {0, -0.5},     {5.5, -2.0},  {9.5, -7.0},
                          {7.5, -13.0}, {0, -16.0},   {-7.5, -14.0}, {-12, -15.0}, {-22, -15.5},
                          {-34, -15.5}, {-46, -15.0}, {-58, -13.0},  {-68, -9.0},  {-75, -4.5},
                          {-82, -2.0},  {-90, 0.0}};
  std::vector<Eigen::Vector3d> out;
  for (const auto& p : xy) out.emplace_back(p[0], p[1], 0.0);
  return out;
}

// Joins the bridge path's end (-90, 0), heading west, to its start (-90, 1.5), heading east,
// for repeated laps (motion.laps): the vessel swings out south-west and loops clockwise round a
// 4 m circle west of the start (x >= -100.5, inside the walls' extent), then bears east onto
// the start line. Five waypoints 60 degrees apart; the path spline rounds the joints, so with
// laps > 1 the path leaves the single lap's line by up to 0.9 m on the 12 m next to a joint;
// from x = -54 round the bridge and back to x = -58 every lap is the single lap's path within
// 2 cm (motion_test).
std::vector<Eigen::Vector3d> bridge_turnaround() {
  const Eigen::Vector3d center(-96.5, 0.75, 0.0);
  const double radius_m = 4.0;
  std::vector<Eigen::Vector3d> out;
  for (const double deg : {-60.0, -120.0, 180.0, 120.0, 60.0}) {
    const double a = deg * M_PI / 180.0;
    out.push_back(center + radius_m * Eigen::Vector3d(std::cos(a), std::sin(a), 0.0));
  }
  return out;
}

std::unique_ptr<AnalyticScene> corridor_scene() {
  auto scene = std::make_unique<AnalyticScene>();
  add_water(scene.get());
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  // Opaque white walls, far longer than the lidar range (seed 000 Fig. 3(b)).
  scene->add(make_box({25, 3.5, -1.75}, I, {180, 0.5, 4.25}, kWhiteWall, "north_wall"));
  scene->add(make_box({25, -3.5, -1.75}, I, {180, 0.5, 4.25}, kWhiteWall, "south_wall"));
  return scene;
}

std::vector<Eigen::Vector3d> corridor_waypoints() {
  std::vector<Eigen::Vector3d> out;
  for (int i = 0; i <= 36; ++i) out.emplace_back(i, 1.0 * std::sin(2.0 * M_PI * i / 12.0), 0.0);
  return out;  // ~38 m winding path
}

void reject_laps(const std::string& scenario, int laps) {
  if (laps != 1)
    throw std::invalid_argument("motion.laps: " + scenario +
                                " flies its path once (no turn-around joins its end to its "
                                "start); expected 1, got " +
                                std::to_string(laps));
}

void add_usv_rig(Scenario* s) {
  s->T_body_sensor["imu"] = Pose3::Identity();
  s->T_body_sensor["dvl"] = pose(rot_x(M_PI), {0.2, 0.0, -0.4});  // boresight down
  s->T_body_sensor["lidar_h"] = pose(Eigen::Matrix3d::Identity(), {0.3, 0.0, 1.0});
  s->T_body_sensor["lidar_v"] = pose(rot_y(M_PI / 2), {0.5, 0.0, 1.2});  // spin axis forward
  // Sonar fan in the body y-z plane, centred 45 deg down to starboard.
  s->T_body_sensor["sonar"] = pose(rot_x(M_PI / 4) * rot_z(-M_PI / 2), {0.4, -0.3, -0.3});
  s->T_body_sensor["cam0"] = pose(forward_looking(), {0.6, 0.0, 0.8});
  s->T_body_sensor["depth"] = pose(Eigen::Matrix3d::Identity(), {0.0, 0.0, -0.2});
  s->T_body_sensor["gnss"] = pose(Eigen::Matrix3d::Identity(), {-0.5, 0.0, 2.0});  // mast top
  s->default_sensors = {"imu", "dvl", "lidar_h", "lidar_v", "sonar", "camera", "depth"};
  s->optional_sensors = {"gnss"};
  // The world frame's origin: on the Welland Canal near St. Catharines (Bridge 13 of seed 000
  // Environment 1), height above the WGS 84 ellipsoid.
  s->origin = {43.1594, -79.1917, 140.0};
  // Seed 000 Table I Kannala-Brandt camera, scaled from 2048x1536 to 512x384 (1/4): rendering
  // 3.2 MP at 20 Hz by ray casting is not affordable; --set camera.rate_hz raises the rate.
  CameraModel& c = s->camera;
  c.kind = CameraModel::Kind::kKannalaBrandt;
  c.width = 512, c.height = 384;
  c.fx = 763.159 / 4, c.fy = 762.408 / 4, c.cx = 1017.926 / 4, c.cy = 791.398 / 4;
  c.distortion = {3.866e-3, 2.494e-2, -2.006e-2, 4.700e-3};
  c.max_theta_rad = 185.0 / 2.0 * M_PI / 180.0;
  s->camera_rate_hz = 2.0;
}

Scenario make_usv(const std::string& name, uint64_t seed, const ScenarioOptions& options) {
  Scenario s;
  s.name = name;
  s.platform = "usv";
  const bool bridge = name == "usv-bridge";
  s.survey = options.survey;
  if (options.survey > 1) {
    if (!bridge)
      throw std::invalid_argument("survey: " + name +
                                  " has no repeated survey with known changes (usv-bridge and "
                                  "hauv-hull have); expected 1, got " +
                                  std::to_string(options.survey));
    s.changes = bridge_changes(seed);
  }
  auto scene = bridge ? bridge_scene(s.changes) : corridor_scene();
  s.analytic = scene.get();
  s.world = std::move(scene);
  MotionOptions motion = options.motion;
  motion.yaw_follows_path = true;
  // The corridor path ends 36 m from its start, facing away from it: a lap joint would need a
  // return leg as long as the lap, which is not the same survey flown again.
  if (!bridge) reject_laps(name, motion.laps);
  s.motion = std::make_unique<PathMotion>(
      SmoothPath(bridge ? repeat_laps(bridge_waypoints(), bridge_turnaround(), motion.laps)
                        : corridor_waypoints()),
      motion, survey_seed(seed, options.survey));
  s.default_duration_s = std::ceil(s.motion->end_time());
  if (!bridge) s.degenerate_axis_world = Eigen::Vector3d::UnitX();
  add_usv_rig(&s);
  if (bridge) {  // the deck (bridge_scene) hides the sky; the piers reflect
    s.gnss_environment.decks.emplace_back(Eigen::Vector2d(-3.5, -21.0), Eigen::Vector2d(3.5, 21.0));
    s.gnss_environment.reflectors = {{0.0, 7.0}, {0.0, -7.0}};
  }
  return s;
}

// ---- hauv-hull -------------------------------------------------------------------------

Pose3 misalignment(Rng& rng, const Eigen::Vector3d& about_cad) {
  // A few cm and ~1 deg between the CAD drawing and the real hull, turning about the
  // surveyed part (a CAD origin 100 m away would turn that 1 deg into metres there).
  Eigen::Vector3d axis(rng.gaussian(), rng.gaussian(), rng.gaussian());
  axis.normalize();
  const double angle = rng.uniform(0.7, 1.3) * M_PI / 180.0;
  const Eigen::Vector3d t(0.03 * rng.gaussian(), 0.03 * rng.gaussian(), 0.03 * rng.gaussian());
  const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, axis).toRotationMatrix();
  return pose(R, t + about_cad - R * about_cad);
}

// Snaps an analytic hull point onto the CAD mesh (along the normal) and places it in world.
bool place_on_real_hull(const MeshBvh& cad_bvh, const SurfacePoint& sp, const Pose3& T_world_cad,
                        Eigen::Vector3d* p_world, Eigen::Vector3d* n_world) {
  MeshHit hit;
  const Eigen::Vector3d origin = sp.p + 0.3 * sp.normal;
  if (!cad_bvh.raycast(origin, -sp.normal, 0.0, 1.0, &hit)) return false;
  Eigen::Vector3d n = cad_bvh.normal(hit.triangle);
  if (n.dot(sp.normal) < 0.0) n = -n;
  *p_world = T_world_cad * (origin - hit.t * sp.normal);
  *n_world = T_world_cad.linear() * n;
  return true;
}

Scenario make_hauv(uint64_t seed, const ScenarioOptions& options) {
  reject_laps("hauv-hull", options.motion.laps);  // it ends at the hull's far end, lanes below
  Scenario s;
  s.name = "hauv-hull";
  s.platform = "hauv";
  s.hull_options = options.hull;
  std::unique_ptr<HullSurface> hull;
  if (options.cad.path.empty()) {
    s.cad_mesh = make_hull_mesh(options.hull);
    hull = std::make_unique<ProceduralHullSurface>(options.hull);
  } else {
    s.cad_mesh = load_cad_hull(options.cad);
    hull = std::make_unique<CadHullSurface>(s.cad_mesh, options.cad.survey_x);
  }
  const HullSurface& shape = *hull;
  Rng rng(seed, Stream::kHull);
  s.T_world_cad = misalignment(rng, shape.survey_center());
  const MeshBvh cad_bvh(s.cad_mesh);

  // Survey lanes along the starboard side and bilge; the vehicle faces the hull (yaw 90 deg)
  // and the tray servo points the DVL and camera along the inward normal.
  const double lanes[] = {0.85, 0.72, 0.59, 0.46, 0.33};
  const Eigen::Vector3d kPivotInBody(0.6, 0.0, -0.1);
  const Eigen::Matrix3d kYaw90 = rot_z(M_PI / 2);
  const double half_span_m = 5.0;
  std::vector<Eigen::Vector3d> waypoints;
  std::vector<double> angles;
  for (int lane = 0; lane < 5; ++lane) {
    for (int k = 0; k <= 10; ++k) {
      const double x = (lane % 2 == 0 ? -1.0 : 1.0) * half_span_m * (1.0 - 0.2 * k);
      const SurfacePoint sp = shape.surface(x, lanes[lane]);
      // The standoff is the DVL's (on the tray pivot, 0.6 m ahead of the body origin).
      waypoints.push_back(sp.p + options.hull_standoff_m * sp.normal - kYaw90 * kPivotInBody);
      angles.push_back(std::atan2(-sp.normal.z(), -sp.normal.y()));
    }
  }
  MotionOptions motion = options.motion;
  motion.yaw_follows_path = false;
  motion.fixed_yaw_rad = M_PI / 2;  // kYaw90
  if (!options.speed_overridden) motion.cruise_speed_mps = 0.25;
  motion.roll_amplitude_rad = 0.005, motion.pitch_amplitude_rad = 0.004,
  motion.heave_amplitude_m = 0.01;
  s.motion = std::make_unique<PathMotion>(SmoothPath(waypoints, {angles}), motion,
                                          survey_seed(seed, options.survey));
  s.default_duration_s = std::ceil(s.motion->end_time());

  // Foreign objects on the real hull (seed 001 Sec. 4: a 0.11 m cylinder, biofouling
  // 0.06-0.18 m), positions jittered by the seed.
  struct Placement {
    ForeignObject::Kind kind;
    double x, sigma;
  };
  const Placement placements[] = {{ForeignObject::Kind::kCylinder, 1.5, 0.72},
                                  {ForeignObject::Kind::kPatch, -2.8, 0.85},
                                  {ForeignObject::Kind::kPatch, 3.2, 0.46},
                                  {ForeignObject::Kind::kPatch, -0.6, 0.33}};
  // Objects are placed first (the scene), then a later survey's changes are applied, then
  // their meshes and landmarks are built. `placed` keeps each object's index in the first
  // survey's list, which names its landmark ids and stream.
  std::vector<std::pair<ForeignObject, size_t>> placed;
  auto clear_of_placed = [&](const ForeignObject& object) {
    return std::all_of(placed.begin(), placed.end(), [&](const auto& p) {
      return (p.first.center - object.center).norm() > p.first.radius_m + object.radius_m + 0.3;
    });
  };
  for (const auto& place : placements) {
    ForeignObject object;
    object.kind = place.kind;
    const double x = place.x + rng.uniform(-0.5, 0.5);
    const SurfacePoint sp = shape.surface(x, place.sigma + rng.uniform(-0.02, 0.02));
    if (!place_on_real_hull(cad_bvh, sp, s.T_world_cad, &object.center, &object.axis))
      throw std::logic_error("hauv-hull: foreign object misses the CAD mesh");
    if (object.kind == ForeignObject::Kind::kCylinder) {
      object.radius_m = 0.08, object.height_m = 0.11;
    } else {
      object.radius_m = rng.uniform(0.1, 0.25), object.height_m = rng.uniform(0.06, 0.18);
    }
    placed.emplace_back(object, placed.size());
  }
  // Fouling patches: uniform over the surveyed band (the lanes' x span and girth), clear of
  // every object placed before by 0.3 m so each stays a shape of its own. Its own random
  // stream, so the default mission does not change.
  if (options.fouling_patches < 0 || options.fouling_patches > kMaxFoulingPatches)
    throw std::invalid_argument("hull.fouling_patches: expected an integer in [0, " +
                                std::to_string(kMaxFoulingPatches) + "], got " +
                                std::to_string(options.fouling_patches));
  // A patch somewhere in the surveyed band; false when it misses the hull or crowds another.
  auto random_patch = [&](Rng& r, ForeignObject* object) {
    object->kind = ForeignObject::Kind::kPatch;
    const double x = r.uniform(-half_span_m, half_span_m);
    const SurfacePoint sp = shape.surface(x, r.uniform(lanes[4] - 0.03, lanes[0] + 0.03));
    object->radius_m = r.uniform(0.1, 0.25);
    object->height_m = r.uniform(0.06, 0.18);
    if (!place_on_real_hull(cad_bvh, sp, s.T_world_cad, &object->center, &object->axis))
      return false;
    return clear_of_placed(*object);
  };
  Rng fouling_rng(seed, Stream::kHull, 1);
  for (int tries = 0; int(placed.size()) < 4 + options.fouling_patches; ++tries) {
    if (tries > 1000 * (options.fouling_patches + 1))
      throw std::invalid_argument("hauv-hull: no room for " +
                                  std::to_string(options.fouling_patches) + " fouling patches");
    ForeignObject object;
    if (random_patch(fouling_rng, &object)) placed.emplace_back(object, placed.size());
  }
  s.survey = options.survey;
  if (options.survey > 1) {
    // A later survey: every patch grew by 2-6 cm in height and radius, the cylinder was
    // removed, one new patch settled. Drawn from the scene seed: every later survey of a seed
    // shows the same changes.
    Rng change_rng(seed, Stream::kHull, 2);
    std::vector<std::pair<ForeignObject, size_t>> later;
    for (auto& [object, index] : placed) {
      SceneChange change;
      change.structure = "hull";
      change.center = object.center;
      change.normal = object.axis;
      change.object = int(index);
      change.height_before_m = object.height_m;
      change.radius_before_m = object.radius_m;
      if (object.kind == ForeignObject::Kind::kCylinder) {
        change.kind = "removed";
        change.height_m = object.height_m;
        change.radius_m = object.radius_m;
        s.changes.push_back(change);
        continue;
      }
      object.height_m += change_rng.uniform(0.02, 0.06);
      object.radius_m += change_rng.uniform(0.02, 0.06);
      change.kind = "grown";
      change.height_m = object.height_m;
      change.radius_m = object.radius_m;
      s.changes.push_back(change);
      later.emplace_back(object, index);
    }
    // The new patch keeps clear of every object of the first survey (the removed one too).
    const size_t first_count = placed.size();
    ForeignObject fresh;
    int tries = 0;
    while (!random_patch(change_rng, &fresh))
      if (++tries > 1000) throw std::invalid_argument("hauv-hull: no room for the new patch");
    placed = later;
    fresh.height_m = std::min(fresh.height_m, 0.12);
    SceneChange change;
    change.kind = "new";
    change.structure = "hull";
    change.center = fresh.center;
    change.normal = fresh.axis;
    change.height_m = fresh.height_m;
    change.radius_m = fresh.radius_m;
    s.changes.push_back(change);
    placed.emplace_back(fresh, first_count);
  }

  TriangleMesh real = transform_mesh(s.cad_mesh, s.T_world_cad);
  std::function<bool(const Eigen::Vector3d&)> in_view;  // procedural: the whole hull
  if (!options.cad.path.empty()) {
    // A real hull has ~100 times the surveyed area: landmarks only where the cameras look.
    const Pose3 T_cad_world = s.T_world_cad.inverse();
    const Eigen::Vector3d center = shape.survey_center();
    in_view = [T_cad_world, center, half_span_m](const Eigen::Vector3d& p_world) {
      const Eigen::Vector3d p = T_cad_world * p_world;
      return std::abs(p.x() - center.x()) <= half_span_m + 4.0 && p.y() <= 1.0 && p.z() <= 0.5;
    };
  }
  const auto hull_landmarks =
      scatter_landmarks(real, options.landmark_density_per_m2, 0.7, true, 0, seed, 0, in_view);
  std::vector<Landmark> landmarks = hull_landmarks;
  for (const auto& [object, index] : placed) {
    const TriangleMesh object_mesh = foreign_object_mesh(object);
    const auto on_object =
        scatter_landmarks(object_mesh, 150.0, 2.0, false, 1000000 + 10000 * int64_t(index),
                          survey_seed(seed, options.survey), 1 + index);
    landmarks.insert(landmarks.end(), on_object.begin(), on_object.end());
    append_mesh(&real, object_mesh);
    s.foreign_objects.push_back(object);
  }
  s.real_mesh_world = real;
  auto world = std::make_unique<HullWorld>(real, std::move(landmarks));
  s.hull_world = world.get();
  s.world = std::move(world);

  // Sensor rig: IMU and depth at the body origin; the tray pivots about body -y through the
  // DVL origin (so the DVL origin does not move when the tray turns).
  s.T_body_sensor["imu"] = Pose3::Identity();
  s.T_body_sensor["depth"] = Pose3::Identity();
  s.has_servo = true;
  s.T_body_servo = pose(Eigen::Matrix3d::Identity(), kPivotInBody);
  s.servo_axis = -Eigen::Vector3d::UnitY();
  s.T_body_sensor["dvl"] = pose(forward_looking(), kPivotInBody);
  s.T_body_sensor["dvl_ranges"] = s.T_body_sensor["dvl"];
  s.T_body_sensor["cam0"] = pose(forward_looking(), {0.65, 0.15, 0.05});
  s.T_body_sensor["servo"] = s.T_body_servo;
  s.tray_sensors = {"dvl", "dvl_ranges", "cam0"};
  s.default_sensors = {"imu", "dvl", "camera", "depth"};
  s.camera = CameraModel{};  // pinhole 640x480, f = 560 px
  s.camera_rate_hz = 2.0;
  return s;
}

}  // namespace

double Scenario::servo_angle(double t_s) const {
  if (!has_servo) return 0.0;
  double s, s_dot, s_ddot, value, d1, d2;
  motion->arc_length(t_s, &s, &s_dot, &s_ddot);
  motion->path().extra_at(0, s, &value, &d1, &d2);
  return value;
}

Pose3 Scenario::T_body_sensor_at(const std::string& sensor, double t_s) const {
  const auto it = T_body_sensor.find(sensor);
  if (it == T_body_sensor.end()) throw std::invalid_argument("no sensor " + sensor + " in " + name);
  if (std::find(tray_sensors.begin(), tray_sensors.end(), sensor) == tray_sensors.end())
    return it->second;
  Pose3 rotation = Pose3::Identity();
  rotation.linear() =
      Eigen::AngleAxisd(servo_angle(t_s), servo_axis.normalized()).toRotationMatrix();
  return T_body_servo * rotation * T_body_servo.inverse() * it->second;
}

uint64_t survey_seed(uint64_t seed, int survey) {
  return survey <= 1 ? seed : splitmix64(seed ^ (uint64_t(survey) * 0x9E3779B97F4A7C15ULL));
}

std::vector<std::string> scenario_names() { return {"usv-bridge", "usv-corridor", "hauv-hull"}; }

Scenario make_scenario(const std::string& name, uint64_t seed, const ScenarioOptions& options) {
  if (name == "usv-bridge" || name == "usv-corridor") {
    if (options.fouling_patches != 0)
      throw std::invalid_argument("hull.fouling_patches: " + name +
                                  " has no hull; expected 0, got " +
                                  std::to_string(options.fouling_patches));
    if (!options.cad.path.empty())
      throw std::invalid_argument("hull.cad: " + name + " has no hull (hauv-hull has)");
    return make_usv(name, seed, options);
  }
  if (options.survey < 1 || options.survey > 100)
    throw std::invalid_argument("survey: expected an integer in [1, 100], got " +
                                std::to_string(options.survey));
  if (name == "hauv-hull") return make_hauv(seed, options);
  throw std::invalid_argument("unknown scenario '" + name +
                              "' (expected usv-bridge, usv-corridor or hauv-hull)");
}

}  // namespace keel::sim
