#include "worker/pipeline/job_extrinsics.h"

#include <memory>
#include <optional>
#include <vector>

#include "proto/calibration.h"
#include "proto/contract_error.h"
#include "worker/io/mission.h"

namespace keel::pipeline {

namespace {

using proto::ContractError;
using proto::ExtrinsicOverride;

Pose3 to_pose(const proto::Extrinsic& e) {
  const auto& q = e.rotation_xyzw;
  const auto& t = e.translation;
  return make_pose(Eigen::Quaterniond(q[3], q[0], q[1], q[2]), Eigen::Vector3d(t[0], t[1], t[2]));
}

proto::Extrinsic to_extrinsic(const Pose3& T) {
  const Eigen::Quaterniond q(T.rotation());
  proto::Extrinsic e;
  e.translation = {T.translation().x(), T.translation().y(), T.translation().z()};
  e.rotation_xyzw = {q.x(), q.y(), q.z(), q.w()};
  return e;
}

std::string sensor_list(const proto::MissionManifest& manifest) {
  std::string out;
  for (const auto& s : manifest.sensors) out += (out.empty() ? "" : ", ") + s.name;
  return out;
}

// T_body_sensor as uploaded: mission.yaml's, else /tf_static's (the bag opened on first need).
class UploadedExtrinsics {
 public:
  explicit UploadedExtrinsics(const io::Mission& mission) : mission_(mission) {}
  std::optional<Pose3> operator()(const std::string& sensor) {
    const proto::SensorSpec& spec = mission_.sensor(sensor);
    if (spec.T_body_sensor) return to_pose(*spec.T_body_sensor);
    if (mission_.bag_path.empty()) return std::nullopt;
    if (!reader_) reader_ = std::make_unique<io::MissionReader>(mission_);
    return reader_->extrinsic(sensor);
  }

 private:
  const io::Mission& mission_;
  std::unique_ptr<io::MissionReader> reader_;
};

}  // namespace

io::Mission load_job_mission(const std::filesystem::path& mission_dir,
                             const nlohmann::json& calibration) {
  io::Mission mission = io::load_mission(mission_dir);
  const std::vector<ExtrinsicOverride> overrides = proto::parse_calibration(calibration);
  if (overrides.empty()) return mission;

  const proto::MissionManifest& manifest = mission.manifest;
  std::map<std::string, const ExtrinsicOverride*> by_sensor;
  for (const auto& o : overrides) {
    if (!manifest.find_sensor(o.sensor))
      throw ContractError(std::string(proto::kCalibrationOption) + "." + o.sensor +
                          ": no sensor '" + o.sensor +
                          "' in the mission (sensors: " + sensor_list(manifest) + ")");
    if (!o.reference.empty() && !manifest.find_sensor(o.reference))
      throw ContractError(o.path() + ": no sensor '" + o.reference +
                          "' in the mission (sensors: " + sensor_list(manifest) + ")");
    by_sensor[o.sensor] = &o;
  }

  // Resolve every override against the mission as uploaded, then write them all.
  UploadedExtrinsics uploaded(mission);
  // A T_body_sensor override is kept as parsed, so it gives the bytes mission.yaml would.
  std::map<std::string, proto::Extrinsic> T_body_sensor;
  for (const auto& o : overrides) {
    if (o.reference.empty()) {
      T_body_sensor[o.sensor] = o.T_reference_sensor;
      continue;
    }
    const Pose3 T_reference_sensor = to_pose(o.T_reference_sensor);
    Pose3 T_body_reference;
    const auto it = by_sensor.find(o.reference);
    if (it != by_sensor.end()) {
      const ExtrinsicOverride& ref = *it->second;
      if (!ref.reference.empty())
        throw ContractError(o.path() + ": the reference '" + o.reference +
                            "' has a relative override itself (" + ref.path() +
                            "); chains of relative overrides are refused: give " + o.reference +
                            "'s T_body_sensor");
      T_body_reference = to_pose(ref.T_reference_sensor);
    } else {
      const std::optional<Pose3> T = uploaded(o.reference);
      if (!T)
        throw ContractError(o.path() + ": the reference '" + o.reference +
                            "' has no T_body_sensor (neither in mission.yaml nor in the bag's "
                            "/tf_static)");
      T_body_reference = *T;
    }
    T_body_sensor[o.sensor] = to_extrinsic(T_body_reference * T_reference_sensor);
  }
  for (auto& spec : mission.manifest.sensors) {
    const auto it = T_body_sensor.find(spec.name);
    if (it == T_body_sensor.end()) continue;
    spec.T_body_sensor = it->second;
    mission.extrinsic_sources[spec.name] = "override " + by_sensor.at(spec.name)->key;
  }
  return mission;
}

io::Mission load_job_mission(const StageContext& context) {
  return load_job_mission(context.mission_dir, context.calibration);
}

namespace {

template <typename Lookup>
JobExtrinsics collect(const io::Mission& mission, Lookup&& lookup) {
  JobExtrinsics out;
  for (const auto& spec : mission.manifest.sensors) {
    const auto source = mission.extrinsic_sources.find(spec.name);
    if (spec.T_body_sensor) {
      out[spec.name] = {to_pose(*spec.T_body_sensor), source != mission.extrinsic_sources.end()
                                                          ? source->second
                                                          : "mission.yaml"};
    } else if (const std::optional<Pose3> T = lookup(spec.name)) {
      out[spec.name] = {*T, "/tf_static"};
    }
  }
  return out;
}

}  // namespace

JobExtrinsics job_extrinsics(const io::MissionReader& reader) {
  return collect(reader.mission(),
                 [&](const std::string& sensor) { return reader.extrinsic(sensor); });
}

JobExtrinsics job_extrinsics(const io::Mission& mission) {
  UploadedExtrinsics uploaded(mission);
  return collect(mission, [&](const std::string& sensor) { return uploaded(sensor); });
}

nlohmann::json calibration_report(const JobExtrinsics& extrinsics) {
  nlohmann::json out = nlohmann::json::object();
  for (const auto& [sensor, e] : extrinsics) {
    const proto::Extrinsic written = to_extrinsic(e.T_body_sensor);
    const nlohmann::json rpy = proto::pose_to_rpy_json(written);
    out[sensor] = {{"source", e.source},
                   {"T_body_sensor", written.to_json()},
                   {"xyz_m", rpy["xyz_m"]},
                   {"rpy_deg", rpy["rpy_deg"]}};
  }
  return out;
}

}  // namespace keel::pipeline
