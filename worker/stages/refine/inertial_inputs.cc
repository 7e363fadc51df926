// Step 3 of stage `refine`: the IMU and DVL samples, extrinsics and noise figures.
#include <cmath>
#include <stdexcept>

#include "worker/pipeline/servo_tray.h"
#include "worker/stages/refine/inputs.h"

namespace keel::pipeline {

namespace {

using proto::SensorType;

std::vector<slam::ImuSample> to_slam(const io::ImuSeries& series) {
  std::vector<slam::ImuSample> out(series.size());
  for (size_t k = 0; k < series.size(); ++k)
    out[k] = {series[k].t_ns, series[k].gyro_rad_s, series[k].accel_m_s2};
  return out;
}

std::vector<slam::DvlSample> to_slam(const io::DvlSeries& series) {
  std::vector<slam::DvlSample> out(series.size());
  for (size_t k = 0; k < series.size(); ++k)
    out[k] = {series[k].t_ns, series[k].velocity_m_s, series[k].valid};
  return out;
}

// A DVL riding a servo tray (seed 001's HAUV) measures in a frame that turns with the tray:
// its samples go into the frame of its manifest extrinsic (angle 0), which the solver holds
// fixed; read as body motion, the tray's turns would corrupt the fusion.
nlohmann::json undo_tray_rotation(const io::MissionReader& reader, const proto::SensorSpec& dvl,
                                  const Pose3& T_body_dvl0, const RefineStageOptions& options,
                                  Inputs& in) {
  const proto::SensorSpec* servo = reader.manifest().find_sensor(dvl.mounted_on);
  if (!servo || servo->type != SensorType::kServo)
    throw std::runtime_error("sensor '" + dvl.name + "': mounted_on '" + dvl.mounted_on +
                             "' is not a servo sensor of the mission");
  const std::optional<Pose3> T_body_servo = reader.extrinsic(servo->name);
  if (!T_body_servo)
    throw std::runtime_error("sensor '" + servo->name +
                             "': no T_body_sensor; the DVL on its tray needs the tray's pivot");
  try {
    const TrayDvlStats stats =
        rotate_tray_dvl(in.solver.dvl, reader.read_servo(servo->name), *T_body_servo,
                        tray_axis(*servo), T_body_dvl0, TimeNs(0.5e9 * options.servo_window_s));
    return {{"servo", servo->name},
            {"samples_turned", stats.rotated},
            {"samples_without_angle", stats.without_angle},
            {"max_angle_deg", stats.max_angle_rad * 180.0 / M_PI}};
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error("sensor '" + dvl.name + "' on '" + servo->name + "': " + e.what());
  }
}

void imu_inputs(const io::MissionReader& reader, const RefineStageOptions& options,
                slam::RefineOptions& solver_options, Inputs& in) {
  const proto::SensorSpec* imu =
      pick_sensor(reader.manifest(), options.imu_sensor, SensorType::kImu, "imu_sensor");
  if (!imu)
    throw std::runtime_error(
        "refine needs an IMU: the mission has no sensor of type imu (mission.yaml sensors)");
  in.solver.imu = to_slam(reader.read_imu(imu->name));
  if (in.solver.imu.size() < 2)
    throw std::runtime_error("sensor '" + imu->name + "': expected IMU samples, found " +
                             std::to_string(in.solver.imu.size()));
  const std::optional<Pose3> T_body_imu = reader.extrinsic(imu->name);
  in.solver.T_body_imu = T_body_imu.value_or(Pose3::Identity());
  if (!T_body_imu)
    in.warnings.push_back("sensor '" + imu->name +
                          "' has no T_body_sensor; the IMU frame is taken as the body frame");
  solver_options.imu_noise = {imu->noise.imu.gyro_noise_density, imu->noise.imu.accel_noise_density,
                              imu->noise.imu.gyro_random_walk, imu->noise.imu.accel_random_walk};
  in.report["imu"] = span_json(in.solver.imu.front().t_ns, in.solver.imu.back().t_ns);
  in.report["imu"]["sensor"] = imu->name;
  in.report["imu"]["samples"] = in.solver.imu.size();
  in.report["imu"]["extrinsic"] = T_body_imu ? "given" : "identity (none given)";
}

void dvl_inputs(const io::MissionReader& reader, const RefineStageOptions& options,
                slam::RefineOptions& solver_options, Inputs& in) {
  const proto::SensorSpec* dvl =
      pick_sensor(reader.manifest(), options.dvl_sensor, SensorType::kDvl, "dvl_sensor");
  if (!dvl)
    throw std::runtime_error(
        "refine fuses a DVL, but the mission has no sensor of type dvl (mission.yaml sensors); "
        "set refine.dvl=false to refine without one");
  const std::optional<Pose3> T_body_dvl = reader.extrinsic(dvl->name);
  if (!T_body_dvl)
    throw std::runtime_error("sensor '" + dvl->name +
                             "': no T_body_sensor (neither in mission.yaml nor /tf_static); "
                             "DVL fusion needs the lever arm and rotation");
  in.solver.dvl = to_slam(reader.read_dvl(dvl->name));
  in.solver.T_body_dvl = *T_body_dvl;
  in.T_body_dvl_manifest = *T_body_dvl;
  in.dvl_sensor = dvl->name;
  solver_options.dvl_noise.velocity_sigma_rel = dvl->noise.dvl.velocity_sigma_rel;
  solver_options.dvl_noise.bias_random_walk_rel = dvl->noise.dvl.bias_random_walk_rel;
  if (in.solver.dvl.empty()) throw std::runtime_error("sensor '" + dvl->name + "': no samples");
  in.report["dvl"] = span_json(in.solver.dvl.front().t_ns, in.solver.dvl.back().t_ns);
  in.report["dvl"]["sensor"] = dvl->name;
  in.report["dvl"]["samples"] = in.solver.dvl.size();
  if (!dvl->mounted_on.empty())
    in.report["dvl"]["servo_tray"] = undo_tray_rotation(reader, *dvl, *T_body_dvl, options, in);
}

}  // namespace

void inertial_inputs(const io::MissionReader& reader, const RefineStageOptions& options,
                     slam::RefineOptions& solver_options, Inputs& in) {
  imu_inputs(reader, options, solver_options, in);
  in.report["dvl"] = nullptr;
  if (options.dvl) dvl_inputs(reader, options, solver_options, in);
}

}  // namespace keel::pipeline
