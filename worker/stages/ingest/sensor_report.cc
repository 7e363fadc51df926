#include "worker/stages/ingest/mission_report.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace keel::pipeline {
namespace {

using nlohmann::json;
using proto::SensorType;
using Progress = std::function<void(double)>;

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

json stream_report(const io::MissionReader& reader, const proto::SensorSpec& s,
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
      // A DVL that publishes beams and a figure of merit (Water Linked A50): velocities solved
      // from three beams, and the figure of merit of the published ones (m/s). Refine weighs
      // DVL samples by the mission's noise figures, not per sample: the figure is shown here.
      const bool beam_level = std::any_of(samples.begin(), samples.end(), [](const auto& x) {
        return x.beams_used > 0 || std::isfinite(x.fom_m_s);
      });
      if (beam_level) {
        extra["three_beam"] = std::count_if(samples.begin(), samples.end(),
                                            [](const auto& x) { return x.beams_used == 3; });
        Summary fom;
        for (const auto& x : samples)
          if (x.valid && std::isfinite(x.fom_m_s)) fom.add(x.fom_m_s);
        extra["fom_m_s"] = fom.to_json();
      }
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
    case SensorType::kGnss: {
      const auto samples = reader.read_gnss(s.name);
      stamps = io::stamps_of(samples);
      size_t by_status[4] = {0, 0, 0, 0};  // NavSatStatus -1..2
      for (const auto& x : samples) ++by_status[x.status + 1];
      extra["fixes_by_status"] = {{"no_fix", by_status[0]},
                                  {"fix", by_status[1]},
                                  {"sbas_fix", by_status[2]},
                                  {"gbas_fix", by_status[3]}};
      break;
    }
    default:
      break;
  }
  json r = stamp_report(stamps, s.rate_hz, options, s.name, warnings);
  r.update(extra);
  return r;
}

// One scan in memory at a time.
json scans_report(const io::MissionReader& reader, const proto::SensorSpec& s,
                  const IngestOptions& options, StageContext& context, json& warnings,
                  const Progress& progress) {
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
    r["time_field"] = {{"field", s.point_time->field},
                       {"unit", proto::to_string(s.point_time->unit)},
                       {"reference", proto::to_string(s.point_time->reference)},
                       {"span_s", time_span.to_json()},
                       {"offset_min_s", time_offset.count ? json(time_offset.min) : json(nullptr)},
                       {"offset_max_s", time_offset.count ? json(time_offset.max) : json(nullptr)}};
    if (s.point_time->is_split()) r["time_field"]["nsec_field"] = s.point_time->nsec_field;
    // Where the stamp falls in the detected sweep [offset_min_s, offset_max_s]: a check of
    // the declared reference (scan_start: first point, scan_end: last point).
    if (time_offset.count) {
      const double span = time_offset.max - time_offset.min;
      const double slack = 0.05 * span;
      r["time_field"]["stamp_marks"] = time_offset.min >= -slack  ? "first point"
                                       : time_offset.max <= slack ? "last point"
                                                                  : "inside the sweep";
    }
  } else if (s.packets) {
    // Raw packets: each point's time is its firing time from the model's table.
    r["packets"] = {{"model", s.packets->model},
                    {"calibration", s.packets->calibration.empty() ? json("factory table")
                                                                   : json(s.packets->calibration)},
                    {"span_s", time_span.to_json()},
                    {"offset_min_s", time_offset.count ? json(time_offset.min) : json(nullptr)},
                    {"offset_max_s", time_offset.count ? json(time_offset.max) : json(nullptr)}};
  }
  return r;
}

// Image headers only (not decoded); a size other than the camera model's is an error.
json images_report(const io::MissionReader& reader, const proto::SensorSpec& s,
                   const IngestOptions& options, StageContext& context, json& warnings,
                   const Progress& progress) {
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

}  // namespace

json sensor_report(const io::MissionReader& reader, const proto::SensorSpec& sensor,
                   const IngestOptions& options, StageContext& context, json& warnings,
                   const Progress& progress) {
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
  const auto& overridden = reader.mission().extrinsic_sources;
  if (overridden.count(sensor.name))
    extrinsic = overridden.at(sensor.name);
  else if (sensor.T_body_sensor)
    extrinsic = "mission.yaml";
  else if (reader.extrinsic(sensor.name))
    extrinsic = "tf_static";
  out["extrinsic"] = extrinsic;
  if (extrinsic == "none" && sensor.type != SensorType::kServo && sensor.type != SensorType::kDepth)
    warnings.push_back(sensor.name + ": no T_body_sensor (neither in mission.yaml nor /tf_static)");
  return out;
}

}  // namespace keel::pipeline
