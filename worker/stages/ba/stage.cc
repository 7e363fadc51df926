// Stage `ba`, as numbered steps:
//   1. options (--set ba.x=v) and the sensors: camera, dvl_ranges, servo, depth; the rig from
//      their extrinsics (docs/mission-format.md "Servo trays": the tray turns about the servo's
//      `axis` through the servo frame, so T_servo_sensor = T_body_servo^-1 T_body_sensor(0));
//   2. keyframes at the camera's images: initial poses, odometry, servo angle, depth, images;
//   3. feature tracks (frontend inside the BA, or the simulator's ground-truth tracks);
//   4. DVL range returns at the keyframes;
//   5. run_model_assisted_ba for the chosen modes;
//   6. artifacts and the report (per mode, Fig. 16 and Fig. 18 figures, x_gM vs truth).
#include "worker/stages/ba/stage.h"
#include "worker/pipeline/report_html_parts.h"
#include "worker/pipeline/stage_options.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

#include "proto/contract_error.h"
#include "worker/ba/model_assisted_ba.h"
#include "core/robust_spread.h"
#include "worker/io/draco/draco_codec.h"
#include "worker/io/mesh/mesh_reader.h"
#include "worker/io/mission_reader.h"
#include "worker/io/text_writer.h"
#include "worker/io/tum.h"
#include "worker/io/yaml_json.h"
#include "worker/mapping/odometry_correction.h"
#include "worker/mapping/stamped_transforms.h"
#include "worker/pipeline/draco_sidecar.h"
#include "worker/pipeline/report.h"
#include "worker/pipeline/servo_tray.h"
#include "worker/pipeline/trajectories_file.h"

namespace keel::pipeline {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using proto::ContractError;
using proto::SensorType;

void local_require(bool ok, const std::string& option, const std::string& expected) {
  if (!ok) throw ContractError("options.ba." + option + ": expected " + expected);
}

// ---- step 1: sensors and rig ----------------------------------------------------------------

const proto::SensorSpec& pick_sensor(const io::MissionReader& reader, const std::string& name,
                                     SensorType type, const std::string& option) {
  const auto& manifest = reader.manifest();
  if (!name.empty()) {
    const proto::SensorSpec* spec = manifest.find_sensor(name);
    if (!spec)
      throw ContractError("options.ba." + option + ": mission has no sensor '" + name + "'");
    if (spec->type != type)
      throw ContractError("options.ba." + option + ": sensor '" + name + "' is a " +
                          proto::to_string(spec->type) + ", expected a " + proto::to_string(type));
    return *spec;
  }
  for (const auto& spec : manifest.sensors)
    if (spec.type == type) return spec;
  throw std::runtime_error("ba: mission.yaml has no " + std::string(proto::to_string(type)) +
                           " sensor (model-assisted BA needs camera, dvl_ranges and servo)");
}

Pose3 require_extrinsic(const io::MissionReader& reader, const std::string& sensor) {
  const std::optional<Pose3> T = reader.extrinsic(sensor);
  if (!T)
    throw std::runtime_error("ba: sensor '" + sensor +
                             "' has no T_body_sensor (neither in mission.yaml nor in /tf_static)");
  return *T;
}

struct Sensors {
  const proto::SensorSpec* camera = nullptr;
  const proto::SensorSpec* dvl = nullptr;
  const proto::SensorSpec* servo = nullptr;
  const proto::SensorSpec* depth = nullptr;  // null when unused or absent
};

Sensors pick_sensors(const io::MissionReader& reader, const BaStageOptions& options) {
  Sensors s;
  s.camera = &pick_sensor(reader, options.camera_sensor, SensorType::kCamera, "camera_sensor");
  s.dvl =
      &pick_sensor(reader, options.dvl_ranges_sensor, SensorType::kDvlRanges, "dvl_ranges_sensor");
  s.servo = &pick_sensor(reader, options.servo_sensor, SensorType::kServo, "servo_sensor");
  if (options.use_depth) {
    if (!options.depth_sensor.empty()) {
      s.depth = &pick_sensor(reader, options.depth_sensor, SensorType::kDepth, "depth_sensor");
    } else {
      for (const auto& spec : reader.manifest().sensors)
        if (spec.type == SensorType::kDepth && spec.is_stream()) {
          s.depth = &spec;
          break;
        }
    }
  }
  for (const proto::SensorSpec* tray : {s.camera, s.dvl})
    if (tray->mounted_on != s.servo->name)
      throw std::runtime_error(
          "ba: sensor '" + tray->name + "' must ride the servo tray '" + s.servo->name +
          "' (mounted_on: " + (tray->mounted_on.empty() ? "none" : tray->mounted_on) + ")");
  return s;
}

ba::BaRig build_rig(const io::MissionReader& reader, const Sensors& s) {
  const proto::CameraSpec& cam = *s.camera->camera;
  if (cam.model != proto::CameraModel::kPinhole ||
      std::any_of(cam.distortion.begin(), cam.distortion.end(), [](double k) { return k != 0; }))
    throw std::runtime_error("ba: camera '" + s.camera->name +
                             "' must be a rectified pinhole camera without distortion");
  ba::BaRig rig;
  rig.camera_top = {cam.fx, cam.fy, cam.cx, cam.cy, cam.width, cam.height};
  const Pose3 T_body_servo = require_extrinsic(reader, s.servo->name);
  rig.T_vehicle_servo_zero = T_body_servo;
  rig.servo_axis = tray_axis(*s.servo);
  rig.T_servo_camera = T_body_servo.inverse() * require_extrinsic(reader, s.camera->name);
  rig.T_servo_dvl = T_body_servo.inverse() * require_extrinsic(reader, s.dvl->name);
  return rig;
}

// ---- step 2: keyframes ----------------------------------------------------------------------

ba::GrayImage to_gray(const io::ImageFrame& frame, const std::string& source) {
  if (frame.bit_depth != 8)
    throw std::runtime_error(source + ": expected an 8-bit image, got " +
                             std::to_string(frame.bit_depth) + "-bit");
  ba::GrayImage gray;
  gray.width = frame.width;
  gray.height = frame.height;
  gray.pixels.resize(size_t(frame.width) * frame.height);
  for (size_t i = 0; i < gray.pixels.size(); ++i) {
    if (frame.channels == 1) {
      gray.pixels[i] = frame.pixels[i];
    } else {  // ITU-R BT.601 luma, as cv::cvtColor does
      const uint8_t* p = &frame.pixels[3 * i];
      gray.pixels[i] = uint8_t(std::lround(0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2]));
    }
  }
  return gray;
}

struct Keyframes {
  std::vector<ba::BaKeyframe> keyframes;
  std::vector<ba::BaOdometry> odometry;
  json report = json::object();
};

Keyframes build_keyframes(const io::MissionReader& reader, const Sensors& s,
                          const BaStageOptions& options, bool decode_images,
                          const StageContext& context) {
  Keyframes out;
  const bool has_map = reader.has_trajectory("map");
  const bool has_odometry = reader.has_trajectory("odometry");
  if (!has_map && !has_odometry)
    throw std::runtime_error(
        "ba needs initial poses: mission.yaml has neither trajectories.map nor "
        "trajectories.odometry");
  Trajectory initial;
  std::optional<mapping::StampedTransforms> odometry;
  if (has_odometry) {
    const Trajectory recorded = reader.read_trajectory("odometry");
    odometry.emplace(recorded, "trajectories.odometry");
    initial = has_map ? mapping::correct_odometry(reader.read_trajectory("map"), recorded).refined
                      : recorded;
    out.report["initial_poses"] = has_map ? "trajectories.odometry corrected by trajectories.map "
                                            "(Algorithm 2, seed 000)"
                                          : "trajectories.odometry as recorded";
  } else {
    initial = reader.read_trajectory("map");
    out.report["initial_poses"] = "trajectories.map, interpolated";
  }
  const mapping::StampedTransforms poses(initial, "initial poses");
  const io::ServoSeries servo = reader.read_servo(s.servo->name);
  io::DepthSeries depth;
  if (s.depth) depth = reader.read_depth(s.depth->name);

  auto images = reader.open_images(s.camera->name);
  io::ImageFrame frame;
  size_t skipped = 0;
  while (images->next(frame, decode_images)) {
    context.check_canceled();
    if (options.max_keyframes > 0 && int(out.keyframes.size()) >= options.max_keyframes) break;
    const auto angle = servo_angle_at(servo, frame.t_ns, TimeNs(0.5e9 * options.servo_window_s));
    if (!poses.covers(frame.t_ns) || !angle || (odometry && !odometry->covers(frame.t_ns))) {
      ++skipped;  // outside the poses' or the servo's span
      continue;
    }
    ba::BaKeyframe k;
    k.t_ns = frame.t_ns;
    k.T_world_vehicle = poses.at(frame.t_ns);
    k.servo_angle_rad = *angle;
    if (s.depth) {
      const auto d = io::interpolate_series(depth, frame.t_ns,
                                            [](const io::DepthSample& x) { return x.depth_m; });
      if (d) {
        // World z is up (docs/mission-format.md: depth positive down); roll and pitch as the
        // SLAM estimated them (Z-Y-X Euler of R_world_vehicle).
        const Eigen::Matrix3d& R = k.T_world_vehicle.linear();
        ba::DepthPitchRoll dpr;
        dpr.z_world_m = -*d;
        dpr.pitch_rad = std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
        dpr.roll_rad = std::atan2(R(2, 1), R(2, 2));
        k.depth_pitch_roll = dpr;
      }
    }
    if (decode_images) k.image_top = to_gray(frame, images->current_source());
    out.keyframes.push_back(std::move(k));
  }
  if (out.keyframes.size() < 2)
    throw std::runtime_error("ba: fewer than 2 camera images of '" + s.camera->name +
                             "' fall inside the poses' and the servo's time span");
  if (odometry) {
    for (size_t i = 1; i < out.keyframes.size(); ++i) {
      ba::BaOdometry o;
      o.from = int(i - 1);
      o.to = int(i);
      o.T_from_to =
          odometry->at(out.keyframes[i - 1].t_ns).inverse() * odometry->at(out.keyframes[i].t_ns);
      out.odometry.push_back(o);
    }
    out.report["odometry"] = "trajectories.odometry increments between keyframes";
  } else {
    out.odometry = ba::odometry_from_initial_poses(out.keyframes);
    out.report["odometry"] = "increments of the initial poses (no recorded odometry)";
  }
  out.report["keyframes"] = out.keyframes.size();
  out.report["images_skipped"] = skipped;
  out.report["depth_sensor"] = s.depth ? json(s.depth->name) : json(nullptr);
  return out;
}

// ---- step 3: ground-truth tracks --------------------------------------------------------------

// truth.yaml `feature_tracks: {<camera>: <csv>}`, CSV `id,t,u,v` at the image stamps.
std::vector<ba::FeatureTrack> ground_truth_tracks(const io::Mission& mission,
                                                  const std::string& camera,
                                                  const std::vector<ba::BaKeyframe>& keyframes) {
  if (mission.ground_truth_path.empty())
    throw ContractError(
        "options.ba.tracks: 'ground_truth' needs the mission's ground_truth: truth.yaml");
  const json truth = io::load_yaml_file(mission.ground_truth_path);
  const json* files = truth.contains("feature_tracks") ? &truth["feature_tracks"] : nullptr;
  if (!files || !files->is_object() || !files->contains(camera))
    throw ContractError("options.ba.tracks: " + mission.ground_truth_path.string() +
                        " has no feature_tracks." + camera);
  const fs::path csv =
      mission.ground_truth_path.parent_path() / (*files)[camera].get<std::string>();
  std::ifstream in(csv);
  if (!in) throw std::runtime_error(csv.string() + ": cannot open");
  std::map<TimeNs, int> keyframe_of;
  for (size_t i = 0; i < keyframes.size(); ++i) keyframe_of[keyframes[i].t_ns] = int(i);
  std::map<int64_t, ba::FeatureTrack> tracks;
  std::string line;
  std::getline(in, line);
  if (line.rfind("id,t,u,v", 0) != 0)
    throw std::runtime_error(csv.string() + ":1: expected header id,t,u,v");
  for (int number = 2; std::getline(in, line); ++number) {
    if (line.empty()) continue;
    std::istringstream row(line);
    std::string id, t, u, v;
    if (!std::getline(row, id, ',') || !std::getline(row, t, ',') || !std::getline(row, u, ',') ||
        !std::getline(row, v, ','))
      throw std::runtime_error(csv.string() + ":" + std::to_string(number) +
                               ": expected 4 columns id,t,u,v");
    try {
      const TimeNs t_ns = std::llround(std::stold(t) * 1e9L);
      // Stamps are printed with limited decimals: match the image within 1 ms.
      auto it = keyframe_of.lower_bound(t_ns - 1000000);
      if (it == keyframe_of.end() || std::llabs(it->first - t_ns) > 1000000) continue;
      ba::FeatureObservation o;
      o.keyframe = it->second;
      o.pixel = Eigen::Vector2d(std::stod(u), std::stod(v));
      auto& track = tracks[std::stoll(id)];
      track.landmark_id = std::stoll(id);
      track.observations.push_back(o);
    } catch (const std::logic_error&) {
      throw std::runtime_error(csv.string() + ":" + std::to_string(number) +
                               ": expected numbers in id,t,u,v, got '" + line + "'");
    }
  }
  std::vector<ba::FeatureTrack> out;
  for (auto& [id, track] : tracks)
    if (track.observations.size() >= 2) out.push_back(std::move(track));
  return out;
}

// ---- step 4: DVL ranges -----------------------------------------------------------------------

std::vector<ba::DvlRange> dvl_ranges_at_keyframes(const io::MissionReader& reader,
                                                  const proto::SensorSpec& dvl,
                                                  const std::vector<ba::BaKeyframe>& keyframes,
                                                  double max_dt_s) {
  if (dvl.beams.size() != 4)
    throw std::runtime_error("ba: dvl_ranges sensor '" + dvl.name + "' needs 4 beams");
  const io::DvlRangesSeries series = reader.read_dvl_ranges(dvl.name);
  std::vector<ba::DvlRange> out;
  const TimeNs max_dt_ns = TimeNs(max_dt_s * 1e9);
  for (size_t k = 0; k < keyframes.size(); ++k) {
    const TimeNs t = keyframes[k].t_ns;
    auto it = std::lower_bound(series.begin(), series.end(), t,
                               [](const io::DvlRangesSample& s, TimeNs x) { return s.t_ns < x; });
    const io::DvlRangesSample* best = nullptr;
    if (it != series.end()) best = &*it;
    if (it != series.begin() && (!best || t - (it - 1)->t_ns < best->t_ns - t)) best = &*(it - 1);
    if (!best || std::llabs(best->t_ns - t) > max_dt_ns) continue;
    for (int b = 0; b < 4; ++b) {
      if (!std::isfinite(best->range_m[b])) continue;  // no return
      ba::DvlRange r;
      r.keyframe = int(k);
      r.beam = b;
      r.direction_dvl =
          Eigen::Vector3d(dvl.beams[b][0], dvl.beams[b][1], dvl.beams[b][2]).normalized();
      r.range_m = best->range_m[b];
      out.push_back(r);
    }
  }
  return out;
}

// ---- step 6: report ---------------------------------------------------------------------------

// p-th percentile (0-100) of ascending `sorted`, linear between ranks.
double percentile_of(const std::vector<double>& sorted, double p) {
  const double pos = p / 100.0 * (sorted.size() - 1);
  const size_t lo = size_t(std::floor(pos));
  const size_t hi = std::min(lo + 1, sorted.size() - 1);
  return sorted[lo] + (pos - lo) * (sorted[hi] - sorted[lo]);
}

std::optional<Pose3> truth_T_world_cad(const io::Mission& mission) {
  if (mission.ground_truth_path.empty()) return std::nullopt;
  const json truth = io::load_yaml_file(mission.ground_truth_path);
  if (!truth.contains("T_world_cad")) return std::nullopt;
  return pose_from_json(truth["T_world_cad"], mission.ground_truth_path.string() + ": T_world_cad");
}

json mode_report(const ba::BaModeResult& m, const std::optional<Pose3>& truth,
                 const BaStageOptions& options) {
  int on_model = 0;
  for (const auto& l : m.landmarks) on_model += l.lambda;
  json r = {
      {"iterations", m.iterations},
      {"unsuccessful_steps", m.unsuccessful_steps},
      {"solve_time_s", m.solve_time_s},
      {"solve_cpu_s", m.solve_cpu_s},
      {"cost_per_iteration", m.cost_per_iteration},
      {"initial_cost", m.initial_cost},
      {"final_cost", m.final_cost},
      {"converged", m.converged},
      {"termination", m.termination},
      {"landmarks", m.landmarks.size()},
      {"landmarks_lambda1", on_model},
      {"lambda1_fraction_per_iteration", m.lambda1_fraction_per_iteration},
      {"dvl_residuals_gicp", residual_stats(ba::residual_values(m.dvl_residuals_initial), options)},
      {"dvl_residuals_final", residual_stats(ba::residual_values(m.dvl_residuals_final), options)},
      {"T_world_model", pose_to_json(m.T_world_model)},
      {"T_servo_camera", pose_to_json(m.T_servo_camera)}};
  if (truth) r["T_world_model_vs_truth"] = model_error(m.T_world_model, *truth);
  r["T_world_model_translation_sigma_model_axes_m"] =
      m.model_translation_sigma_m.empty() ? json(nullptr) : json(m.model_translation_sigma_m);
  return r;
}

// Fig. 18(a)-(b) as a table: state (gicp | ba), keyframe time, hit point in the CAD frame,
// measured minus predicted range.
void write_dvl_residuals(const fs::path& path, const ba::BaModeResult& m,
                         const std::vector<ba::BaKeyframe>& keyframes) {
  io::TextWriter w(path);
  w.text("state,t,x_model_m,y_model_m,z_model_m,residual_m\n");
  for (const auto& [state, beams] :
       {std::pair{"gicp", &m.dvl_residuals_initial}, std::pair{"ba", &m.dvl_residuals_final}}) {
    for (const ba::DvlBeamResidual& b : *beams) {
      w.text(state).text(",").seconds(keyframes[b.keyframe].t_ns);
      for (double x : {b.hit_model.x(), b.hit_model.y(), b.hit_model.z(), b.residual_m})
        w.text(",").number(x);
      w.text("\n");
    }
  }
  w.close();
}

// trajectories.json's `ba`: the keyframe poses in the CAD model frame (x_gM^-1 T_world_vehicle),
// where the hull products of ba are; T_world_model places them in the world.
void write_model_frame_trajectory(const fs::path& work_dir, const ba::BaModeResult& m,
                                  const std::vector<ba::BaKeyframe>& keyframes) {
  const Pose3 T_model_world = m.T_world_model.inverse();
  Trajectory in_model;
  for (size_t i = 0; i < keyframes.size(); ++i)
    in_model.push_back({keyframes[i].t_ns, T_model_world * m.T_world_vehicle[i]});
  add_to_trajectories_file(work_dir, {{"ba", "model", in_model, {}}}, m.T_world_model);
}

// cad_model.drc (the job's CAD mesh as given, model frame) and its sidecar; report figures.
json write_cad_model(const fs::path& work_dir, const TriangleMesh& cad,
                     const BaStageOptions& options) {
  io::DracoOptions draco;
  draco.position_bits = options.cad_draco_position_bits;
  const io::DracoEncoded encoded = io::encode_draco_mesh(cad, {}, draco);
  io::write_draco_file(work_dir / kCadModelFile, encoded.bytes);
  return {{"file", kCadModelFile},
          {"bytes", encoded.bytes.size()},
          {"max_position_error_m", encoded.max_position_error_m},
          {"position_error_bound_m", encoded.position_error_bound_m},
          {"sidecar", write_draco_sidecar(work_dir, kCadModelFile, encoded.summary, "model")}};
}

BaSolution solution_of(const ba::BaModeResult& m, const std::vector<ba::BaKeyframe>& keyframes) {
  BaSolution s;
  s.mode = ba::to_string(m.mode);
  s.T_world_model = m.T_world_model;
  for (const auto& k : keyframes) s.t_ns.push_back(k.t_ns);
  s.T_world_camera = m.T_world_camera;
  for (const auto& l : m.landmarks) {
    const ba::InspectionPoint at = ba::inspection_point(l);
    s.landmarks.push_back({l.id, at.position_world, at.signed_distance_m, l.lambda, l.keyframes});
  }
  return s;
}

class BaStage : public Stage {
 public:
  std::string name() const override { return "ba"; }
  std::string report_html(const report_html::Ref& section,
                          const ReportHtmlInputs& inputs) const override {
    return report_html::ba_section(section);
  }

  StageResult run(StageContext& context) override {
    const BaStageOptions options = BaStageOptions::from_json(context.options);
    const io::Mission mission = io::load_mission(context.mission_dir);
    io::MissionReader reader(mission);
    const Sensors sensors = pick_sensors(reader, options);

    ba::BaProblem problem;
    problem.rig = build_rig(reader, sensors);
    const bool frontend = options.tracks == "frontend";
    Keyframes keyframes = build_keyframes(reader, sensors, options, frontend, context);
    problem.keyframes = std::move(keyframes.keyframes);
    problem.odometry = std::move(keyframes.odometry);
    if (!frontend)
      problem.tracks = ground_truth_tracks(mission, sensors.camera->name, problem.keyframes);
    problem.dvl_ranges =
        dvl_ranges_at_keyframes(reader, *sensors.dvl, problem.keyframes, options.dvl_max_dt_s);
    const fs::path cad = !context.cad_path.empty() ? context.cad_path : mission.cad_mesh_path;
    if (cad.empty())
      throw std::runtime_error(
          "ba needs a CAD mesh: the job has none and mission.yaml has no "
          "cad_mesh");
    problem.cad_mesh = io::read_mesh(cad);
    context.progress(0.1);
    context.check_canceled();
    context.log("ba: " + std::to_string(problem.keyframes.size()) + " keyframes, " +
                (frontend ? std::string("frontend tracks")
                          : std::to_string(problem.tracks.size()) + " ground-truth tracks") +
                ", " + std::to_string(problem.dvl_ranges.size()) + " DVL returns");

    ba::BaOptions ba_options;
    ba_options.modes = options.modes();
    ba_options.max_iterations = options.max_iterations;
    ba_options.function_tolerance = options.function_tolerance;
    ba_options.num_threads = options.threads;
    ba_options.linear_solver = options.linear_solver;
    ba_options.dvl_range_normal = options.dvl_range_normal == "facet"
                                      ? ba::DvlRangeNormal::kFacet
                                      : ba::DvlRangeNormal::kInterpolated;
    ba_options.triangulation.max_reprojection_px = options.triangulation_max_reprojection_px;
    const ba::BaResult result = ba::run_model_assisted_ba(problem, ba_options);
    context.progress(0.9);

    // Step 6: artifacts (proposed mode, else the last one run) and report.
    const ba::BaModeResult* chosen = result.find(ba::BaMode::kProposed);
    if (!chosen) chosen = &result.modes.back();
    Trajectory refined;
    for (size_t i = 0; i < problem.keyframes.size(); ++i)
      refined.push_back({problem.keyframes[i].t_ns, chosen->T_world_vehicle[i]});
    io::write_tum(context.work_dir / kBaTrajectoryFile, refined);
    write_json_atomically(
        context.work_dir / kBaSolutionFile,
        nlohmann::ordered_json(ba_solution_to_json(solution_of(*chosen, problem.keyframes))));

    write_dvl_residuals(context.work_dir / kBaDvlResidualsFile, *chosen, problem.keyframes);
    write_model_frame_trajectory(context.work_dir, *chosen, problem.keyframes);
    const json cad_model = write_cad_model(context.work_dir, problem.cad_mesh, options);

    const std::optional<Pose3> truth = truth_T_world_cad(mission);
    StageResult out;
    out.artifacts = {kBaTrajectoryFile, kBaSolutionFile, kBaDvlResidualsFile,
                     kTrajectoriesFile, kCadModelFile,   cad_model["sidecar"].get<std::string>()};
    json& r = out.report;
    r["input"] = keyframes.report;
    r["input"]["tracks_source"] = frontend ? "frontend (SIFT on the images, Sec. 2.7)"
                                           : "ground_truth (truth.yaml feature_tracks)";
    r["input"]["camera"] = sensors.camera->name;
    r["input"]["dvl_ranges"] = sensors.dvl->name;
    r["input"]["servo"] = sensors.servo->name;
    r["input"]["cad_mesh"] = cad.filename().string();
    r["frontend"] = {{"ran", result.frontend.ran},
                     {"keyframe_pairs_matched", result.frontend.keyframe_pairs_matched},
                     {"keyframe_pairs_verified", result.frontend.keyframe_pairs_verified},
                     {"verified_matches", result.frontend.verified_matches},
                     {"tracks", result.frontend.tracks}};
    r["initialisation"] = {{"ran", result.initialisation.ran},
                           {"iterations", result.initialisation.iterations},
                           {"solve_time_s", result.initialisation.solve_time_s},
                           {"initial_cost", result.initialisation.initial_cost},
                           {"final_cost", result.initialisation.final_cost}};
    r["tracks_in"] = result.tracks_in;
    r["landmarks_triangulated"] = result.landmarks_triangulated;
    r["landmarks_dropped_after_initialisation"] = result.landmarks_dropped_after_initialisation;
    r["observations_dropped_after_initialisation"] =
        result.observations_dropped_after_initialisation;
    r["post_initialisation_gate_px"] = result.post_initialisation_gate_px;
    r["dvl_ranges_in"] = result.dvl_ranges_in;
    r["dvl_ranges_used"] = result.dvl_ranges_used;
    r["gicp"] = {{"ran", result.gicp_ran},
                 {"converged", result.gicp_converged},
                 {"fitness_m2", result.gicp_fitness},
                 {"T_world_model", pose_to_json(result.T_world_model_initial)}};
    if (truth)
      r["gicp"]["T_world_model_vs_truth"] = model_error(result.T_world_model_initial, *truth);
    r["modes"] = json::object();
    for (const auto& m : result.modes)
      r["modes"][ba::to_string(m.mode)] = mode_report(m, truth, options);
    r["solution_mode"] = ba::to_string(chosen->mode);
    r["cad_model"] = cad_model;
    context.progress(1.0);
    return out;
  }
};

}  // namespace

// ---- options ----------------------------------------------------------------------------------

BaStageOptions BaStageOptions::from_json(const json& options) {
  BaStageOptions o;
  if (options.is_null()) return o;
  StageOptionReader r(options, "ba");
  o.mode = r.optional<std::string>("mode", o.mode);
  o.tracks = r.optional<std::string>("tracks", o.tracks);
  o.camera_sensor = r.optional<std::string>("camera_sensor", o.camera_sensor);
  o.dvl_ranges_sensor = r.optional<std::string>("dvl_ranges_sensor", o.dvl_ranges_sensor);
  o.servo_sensor = r.optional<std::string>("servo_sensor", o.servo_sensor);
  o.depth_sensor = r.optional<std::string>("depth_sensor", o.depth_sensor);
  o.use_depth = r.optional<bool>("use_depth", o.use_depth);
  o.dvl_max_dt_s = r.optional<double>("dvl_max_dt_s", o.dvl_max_dt_s);
  o.servo_window_s = r.optional<double>("servo_window_s", o.servo_window_s);
  o.triangulation_max_reprojection_px =
      r.optional<double>("triangulation_max_reprojection_px", o.triangulation_max_reprojection_px);
  o.max_keyframes = r.optional<int>("max_keyframes", o.max_keyframes);
  o.max_iterations = r.optional<int>("max_iterations", o.max_iterations);
  o.function_tolerance = r.optional<double>("function_tolerance", o.function_tolerance);
  o.threads = r.optional<int>("threads", o.threads);
  o.linear_solver = r.optional<std::string>("linear_solver", o.linear_solver);
  o.dvl_range_normal = r.optional<std::string>("dvl_range_normal", o.dvl_range_normal);
  o.histogram_bin_m = r.optional<double>("histogram_bin_m", o.histogram_bin_m);
  o.histogram_range_m = r.optional<double>("histogram_range_m", o.histogram_range_m);
  o.cad_draco_position_bits = r.optional<int>("cad_draco_position_bits", o.cad_draco_position_bits);
  r.finish();
  local_require(o.mode == "all" || o.mode == "proposed" || o.mode == "geva" || o.mode == "naive", "mode",
          "proposed, geva, naive or all, got '" + o.mode + "'");
  local_require(o.tracks == "frontend" || o.tracks == "ground_truth", "tracks",
          "frontend or ground_truth, got '" + o.tracks + "'");
  local_require(o.use_depth || o.depth_sensor.empty(), "depth_sensor", "empty when use_depth is false");
  local_require(std::isfinite(o.dvl_max_dt_s) && o.dvl_max_dt_s > 0, "dvl_max_dt_s", "a positive number");
  local_require(
      std::isfinite(o.triangulation_max_reprojection_px) && o.triangulation_max_reprojection_px > 0,
      "triangulation_max_reprojection_px", "a positive number");
  local_require(std::isfinite(o.servo_window_s) && o.servo_window_s >= 0, "servo_window_s",
          "a number >= 0");
  local_require(o.max_keyframes >= 0, "max_keyframes", ">= 0");
  local_require(o.max_iterations > 0, "max_iterations", "> 0");
  local_require(
      std::isfinite(o.function_tolerance) && o.function_tolerance > 0 && o.function_tolerance < 1,
      "function_tolerance", "a number in (0, 1)");
  local_require(o.threads > 0, "threads", "> 0");
  local_require(o.linear_solver == "sparse_schur" || o.linear_solver == "iterative_schur" ||
              o.linear_solver == "dense_schur",
          "linear_solver",
          "sparse_schur, iterative_schur or dense_schur, got '" + o.linear_solver + "'");
  local_require(o.dvl_range_normal == "interpolated" || o.dvl_range_normal == "facet", "dvl_range_normal",
          "interpolated or facet, got '" + o.dvl_range_normal + "'");
  local_require(std::isfinite(o.histogram_bin_m) && o.histogram_bin_m > 0, "histogram_bin_m",
          "a positive number");
  local_require(std::isfinite(o.histogram_range_m) && o.histogram_range_m >= o.histogram_bin_m &&
              o.histogram_range_m / o.histogram_bin_m <= 10000,
          "histogram_range_m", "a number in [histogram_bin_m, 10000 * histogram_bin_m]");
  local_require(o.cad_draco_position_bits >= 1 && o.cad_draco_position_bits <= 30,
          "cad_draco_position_bits", "an integer in [1, 30]");
  return o;
}

json residual_stats(std::vector<double> r, const BaStageOptions& options) {
  json out = {{"count", r.size()}};
  if (r.empty()) return out;
  double sum = 0, sum2 = 0;
  for (double x : r) sum += x;
  const double mean = sum / r.size();
  for (double x : r) sum2 += (x - mean) * (x - mean);
  std::sort(r.begin(), r.end());
  out["mean_m"] = mean;
  out["sigma_m"] = std::sqrt(sum2 / r.size());
  // The spread of the bulk, blind to the few beams that see structure the model lacks (a
  // fouling patch 5-18 cm proud).
  out["robust_sigma_m"] = robust_spread(r).sigma;
  json pct = json::object();
  for (double p : {5.0, 25.0, 50.0, 75.0, 95.0})
    pct["p" + std::to_string(int(p))] = percentile_of(r, p);
  out["percentiles_m"] = pct;
  const int bins = int(std::lround(2.0 * options.histogram_range_m / options.histogram_bin_m));
  std::vector<int> counts(bins, 0);
  int below = 0, above = 0;
  for (double x : r) {
    const int b = int(std::floor((x + options.histogram_range_m) / options.histogram_bin_m));
    if (b < 0)
      ++below;
    else if (b >= bins)
      ++above;
    else
      ++counts[b];
  }
  out["histogram"] = {{"first_edge_m", -options.histogram_range_m},
                      {"bin_m", options.histogram_bin_m},
                      {"counts", counts},
                      {"below", below},
                      {"above", above}};
  return out;
}

std::vector<ba::BaMode> BaStageOptions::modes() const {
  if (mode == "all") return {ba::BaMode::kNaive, ba::BaMode::kGeva, ba::BaMode::kProposed};
  return {ba::ba_mode_from_string(mode)};
}

nlohmann::json model_error(const Pose3& estimate, const Pose3& truth) {
  const double angle =
      Eigen::AngleAxisd(truth.linear().transpose() * estimate.linear()).angle() * 180.0 / M_PI;
  // Also per axis of the true model frame: along a ship hull's length (x) the mid-body is
  // nearly prismatic, so neither the DVL ranges nor the surface factors fix x_gM there.
  const Eigen::Vector3d in_model =
      truth.linear().transpose() * (estimate.translation() - truth.translation());
  return {{"translation_error_m", in_model.norm()},
          {"translation_error_model_axes_m", {in_model.x(), in_model.y(), in_model.z()}},
          {"rotation_error_deg", angle}};
}

std::unique_ptr<Stage> make_ba_stage() { return std::make_unique<BaStage>(); }

}  // namespace keel::pipeline
