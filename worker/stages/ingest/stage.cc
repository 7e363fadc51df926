// Stage `ingest` (docs/mission-format.md): loads mission.yaml, reads every stream, every scan
// and every image header once (one scan in memory at a time) and reports per sensor what the
// bundle holds: counts, time spans, measured vs nominal rate, gaps, point statistics and the
// span of the per-point time field; per trajectory: poses, span and path length; with a CAD
// mesh, its size, area, closedness, degenerate triangles and a units check (io::check_mesh).
#include "worker/stages/ingest/stage.h"
#include "worker/pipeline/report_html_parts.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "proto/contract_error.h"
#include "worker/io/display_path.h"
#include "worker/io/mesh/mesh_check.h"
#include "worker/io/mesh/mesh_reader.h"
#include "worker/io/mission_reader.h"
#include "worker/pipeline/stage_options.h"

namespace keel::pipeline {

namespace {

using nlohmann::json;
using proto::SensorType;

struct IngestOptions {
  double gap_factor = 2.5;      // a gap is an interval longer than gap_factor nominal periods
  double rate_tolerance = 0.2;  // measured rate off nominal by more than this: a warning

  static IngestOptions from_json(const json& options) {
    IngestOptions o;
    if (options.is_null()) return o;
    StageOptionReader r(options, "ingest");
    o.gap_factor = r.optional<double>("gap_factor", o.gap_factor);
    o.rate_tolerance = r.optional<double>("rate_tolerance", o.rate_tolerance);
    r.finish();
    if (!(o.gap_factor > 1.0))
      throw proto::ContractError("options.ingest.gap_factor: expected > 1");
    if (!(o.rate_tolerance > 0.0))
      throw proto::ContractError("options.ingest.rate_tolerance: expected > 0");
    return o;
  }
};

// Count, span, measured rate and gaps of a stamp series (strictly increasing).
json stamp_report(const std::vector<TimeNs>& stamps, double nominal_rate_hz,
                  const IngestOptions& options, const std::string& name, json& warnings) {
  json r = {{"count", stamps.size()}};
  if (stamps.empty()) {
    warnings.push_back(name + ": no data");
    return r;
  }
  const double duration_s = ns_to_seconds(stamps.back() - stamps.front());
  r["t_first_s"] = ns_to_seconds(stamps.front());
  r["t_last_s"] = ns_to_seconds(stamps.back());
  r["duration_s"] = duration_s;
  const double measured =
      duration_s > 0.0 ? static_cast<double>(stamps.size() - 1) / duration_s : 0.0;
  r["rate_hz_measured"] = measured;
  if (nominal_rate_hz > 0.0) {
    r["rate_hz_nominal"] = nominal_rate_hz;
    const double threshold_s = options.gap_factor / nominal_rate_hz;
    size_t gaps = 0;
    double longest_s = 0.0;
    for (size_t i = 1; i < stamps.size(); ++i) {
      const double dt = ns_to_seconds(stamps[i] - stamps[i - 1]);
      if (dt > threshold_s) ++gaps;
      longest_s = std::max(longest_s, dt);
    }
    r["gaps"] = {{"threshold_s", threshold_s}, {"count", gaps}, {"longest_interval_s", longest_s}};
    if (stamps.size() > 1 &&
        std::abs(measured - nominal_rate_hz) > options.rate_tolerance * nominal_rate_hz)
      warnings.push_back(name + ": measured rate " + std::to_string(measured) + " Hz, nominal " +
                         std::to_string(nominal_rate_hz) + " Hz");
    if (gaps > 0)
      warnings.push_back(name + ": " + std::to_string(gaps) + " gaps longer than " +
                         std::to_string(threshold_s) + " s (longest " + std::to_string(longest_s) +
                         " s)");
  }
  return r;
}

// min / mean / max of a series of values.
struct Summary {
  double min = std::numeric_limits<double>::infinity();
  double max = -std::numeric_limits<double>::infinity();
  double sum = 0.0;
  size_t count = 0;
  void add(double x) {
    min = std::min(min, x);
    max = std::max(max, x);
    sum += x;
    ++count;
  }
  json to_json() const {
    if (count == 0) return nullptr;
    return {{"min", min}, {"mean", sum / static_cast<double>(count)}, {"max", max}};
  }
};

class IngestStage : public Stage {
 public:
  std::string name() const override { return "ingest"; }
  std::string report_html(const report_html::Ref& section,
                          const ReportHtmlInputs& inputs) const override {
    return report_html::ingest_section(section);
  }

  StageResult run(StageContext& context) override {
    const IngestOptions options = IngestOptions::from_json(context.options);
    io::MissionReader reader(io::load_mission(context.mission_dir));
    const auto& manifest = reader.manifest();
    json warnings = json::array();
    json sensors = json::object();
    const std::filesystem::path cad_path =
        !context.cad_path.empty() ? context.cad_path : reader.mission().cad_mesh_path;
    const size_t units =
        manifest.sensors.size() + manifest.trajectories.size() + (cad_path.empty() ? 1 : 2);
    size_t done = 0;
    auto progress = [&](double within) {
      context.progress((done + within) / static_cast<double>(units));
    };

    for (const auto& sensor : manifest.sensors) {
      context.check_canceled();
      sensors[sensor.name] =
          sensor_report(reader, sensor, options, context, warnings, [&](double f) { progress(f); });
      context.log(sensor.name + " (" + proto::to_string(sensor.type) +
                  "): " + std::to_string(sensors[sensor.name]["count"].get<size_t>()) + " records");
      ++done;
      progress(0.0);
    }

    json trajectories = json::object();
    for (const auto& [name, spec] : manifest.trajectories) {
      context.check_canceled();
      trajectories[name] = trajectory_report(reader.read_trajectory(name), options, name, warnings);
      trajectories[name]["source"] = spec.topic.empty() ? spec.file : "topic " + spec.topic;
      ++done;
      progress(0.0);
    }
    context.check_canceled();
    const auto loops = reader.read_loop_closures();
    json cad = nullptr;
    if (!cad_path.empty()) {
      ++done;
      progress(0.0);
      context.check_canceled();
      cad = cad_report(cad_path, warnings);
      context.log("cad: " + std::to_string(cad["num_faces"].get<size_t>()) + " triangles, " +
                  (cad["closed"].get<bool>() ? "closed" : "open"));
    }
    context.progress(1.0);

    StageResult result;
    result.report = {
        {"mission",
         {{"name", manifest.name},
          {"platform", proto::to_string(manifest.platform)},
          {"body_frame", manifest.body_frame},
          {"world_frame", manifest.world_frame},
          {"bag", manifest.bag.empty() ? json(nullptr) : json(manifest.bag)},
          {"cad_mesh", manifest.cad_mesh.empty() ? json(nullptr) : json(manifest.cad_mesh)},
          {"ground_truth",
           manifest.ground_truth.empty() ? json(nullptr) : json(manifest.ground_truth)}}},
        {"sensors", sensors},
        {"trajectories", trajectories},
        {"loop_closures", loops.size()},
        {"cad", cad},
        {"warnings", warnings}};
    return result;
  }

 private:
  template <typename Progress>
  static json sensor_report(const io::MissionReader& reader, const proto::SensorSpec& sensor,
                            const IngestOptions& options, StageContext& context, json& warnings,
                            Progress&& progress) {
    json r;
    if (sensor.is_scans())
      r = scans_report(reader, sensor, options, context, warnings, progress);
    else if (sensor.is_images())
      r = images_report(reader, sensor, options, context, warnings, progress);
    else
      r = stream_report(reader, sensor, options, warnings);
    json out = {{"type", proto::to_string(sensor.type)},
                {"source", !sensor.topic.empty()   ? "topic " + sensor.topic
                           : !sensor.file.empty()  ? sensor.file
                           : !sensor.scans.empty() ? sensor.scans
                                                   : sensor.images}};
    out.update(r);
    std::string extrinsic = "none";
    if (sensor.T_body_sensor)
      extrinsic = "mission.yaml";
    else if (reader.extrinsic(sensor.name))
      extrinsic = "tf_static";
    out["extrinsic"] = extrinsic;
    if (extrinsic == "none" && sensor.type != SensorType::kServo &&
        sensor.type != SensorType::kDepth)
      warnings.push_back(sensor.name +
                         ": no T_body_sensor (neither in mission.yaml nor /tf_static)");
    return out;
  }

  static json stream_report(const io::MissionReader& reader, const proto::SensorSpec& s,
                            const IngestOptions& options, json& warnings) {
    std::vector<TimeNs> stamps;
    json extra = json::object();
    switch (s.type) {
      case SensorType::kImu:
        stamps = io::stamps_of(reader.read_imu(s.name));
        break;
      case SensorType::kDvl: {
        const auto samples = reader.read_dvl(s.name);
        stamps = io::stamps_of(samples);
        extra["invalid"] =
            std::count_if(samples.begin(), samples.end(), [](const auto& x) { return !x.valid; });
        break;
      }
      case SensorType::kDvlRanges: {
        const auto samples = reader.read_dvl_ranges(s.name);
        stamps = io::stamps_of(samples);
        size_t missing = 0;
        for (const auto& x : samples)
          for (double range : x.range_m) missing += std::isnan(range);
        extra["beam_returns_missing"] = missing;
        break;
      }
      case SensorType::kDepth:
        stamps = io::stamps_of(reader.read_depth(s.name));
        break;
      case SensorType::kServo:
        stamps = io::stamps_of(reader.read_servo(s.name));
        break;
      default:
        break;
    }
    json r = stamp_report(stamps, s.rate_hz, options, s.name, warnings);
    r.update(extra);
    return r;
  }

  template <typename Progress>
  static json scans_report(const io::MissionReader& reader, const proto::SensorSpec& s,
                           const IngestOptions& options, StageContext& context, json& warnings,
                           Progress&& progress) {
    auto source = reader.open_scans(s.name);
    const size_t total = source->size();
    std::vector<TimeNs> stamps;
    Summary points, time_span, time_offset;
    size_t points_total = 0;
    PointCloud cloud;
    while (true) {
      context.check_canceled();
      if (!source->next(cloud)) break;
      stamps.push_back(cloud.t_ns);
      points.add(static_cast<double>(cloud.size()));
      points_total += cloud.size();
      if (cloud.has_time() && !cloud.empty()) {
        const auto [lo, hi] = std::minmax_element(cloud.time_s.begin(), cloud.time_s.end());
        time_span.add(*hi - *lo);
        time_offset.add(*lo);
        time_offset.add(*hi);
      }
      if (total > 0) progress(static_cast<double>(stamps.size()) / static_cast<double>(total));
    }
    json r = stamp_report(stamps, s.rate_hz, options, s.name, warnings);
    r["points"] = {{"total", points_total}, {"per_scan", points.to_json()}};
    if (s.point_time) {
      r["time_field"] = {
          {"field", s.point_time->field},
          {"unit", proto::to_string(s.point_time->unit)},
          {"reference", proto::to_string(s.point_time->reference)},
          {"span_s", time_span.to_json()},
          {"offset_min_s", time_offset.count ? json(time_offset.min) : json(nullptr)},
          {"offset_max_s", time_offset.count ? json(time_offset.max) : json(nullptr)}};
    }
    return r;
  }

  template <typename Progress>
  static json images_report(const io::MissionReader& reader, const proto::SensorSpec& s,
                            const IngestOptions& options, StageContext& context, json& warnings,
                            Progress&& progress) {
    auto source = reader.open_images(s.name);
    const size_t total = source->size();
    std::vector<TimeNs> stamps;
    io::ImageFrame frame;
    json sizes = json::array();
    while (true) {
      context.check_canceled();
      if (!source->next(frame, /*decode=*/false)) break;
      stamps.push_back(frame.t_ns);
      if (s.camera && (frame.width != s.camera->width || frame.height != s.camera->height))
        throw std::runtime_error(
            source->current_source() + ": image is " + std::to_string(frame.width) + "x" +
            std::to_string(frame.height) + ", camera '" + s.name + "' in mission.yaml is " +
            std::to_string(s.camera->width) + "x" + std::to_string(s.camera->height));
      const json size = {frame.width, frame.height, frame.channels, frame.bit_depth};
      if (std::find(sizes.begin(), sizes.end(), size) == sizes.end()) sizes.push_back(size);
      if (total > 0) progress(static_cast<double>(stamps.size()) / static_cast<double>(total));
    }
    json r = stamp_report(stamps, s.rate_hz, options, s.name, warnings);
    r["formats"] = sizes;  // [width, height, channels, bit_depth] seen
    return r;
  }

  // A mesh that cannot serve as a CAD prior fails here, naming the problem (read_mesh refuses
  // non-finite vertices and meshes without faces, naming the file and line); what it can
  // serve with goes into the report and the warnings.
  static json cad_report(const std::filesystem::path& path, json& warnings) {
    const TriangleMesh mesh = io::read_mesh(path);
    const io::MeshCheckReport check = io::check_mesh(mesh);
    if (check.degenerate_faces() == check.num_faces)
      throw std::runtime_error(io::display_path(path) + ": all " + std::to_string(check.num_faces) +
                               " triangles are degenerate (no surface to align to)");
    json r = check.to_json();
    r["file"] = path.filename().string();
    for (const auto& w : check.warnings) warnings.push_back("cad: " + w.message);
    return r;
  }

  static json trajectory_report(const Trajectory& trajectory, const IngestOptions& options,
                                const std::string& name, json& warnings) {
    std::vector<TimeNs> stamps;
    double path_length_m = 0.0;
    for (size_t i = 0; i < trajectory.size(); ++i) {
      stamps.push_back(trajectory[i].t_ns);
      if (i > 0)
        path_length_m += (trajectory[i].T_world_body.translation() -
                          trajectory[i - 1].T_world_body.translation())
                             .norm();
    }
    json r = stamp_report(stamps, 0.0, options, "trajectories." + name, warnings);
    r["path_length_m"] = path_length_m;
    return r;
  }
};

}  // namespace

std::unique_ptr<Stage> make_ingest_stage() { return std::make_unique<IngestStage>(); }

}  // namespace keel::pipeline
