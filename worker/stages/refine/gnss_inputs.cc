// Step 5b of stage `refine`: GNSS fixes into the world frame (the local ENU frame at
// mission.yaml's `origin`, core/geodesy.h), and the report of what the gate did with them.
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/geodesy.h"
#include "worker/stages/refine/inputs.h"

namespace keel::pipeline {

void gnss_inputs(const io::MissionReader& reader, const RefineStageOptions& options, Inputs& in) {
  const auto& manifest = reader.manifest();
  const proto::SensorSpec* sensor =
      pick_sensor(manifest, options.gnss_sensor, proto::SensorType::kGnss, "gnss_sensor");
  if (!sensor || !options.gnss) return;
  if (!manifest.origin)  // the manifest's own check makes this unreachable from mission.yaml
    throw std::runtime_error("refine: gnss sensor '" + sensor->name + "' needs `origin:`");
  const auto extrinsic = reader.extrinsic(sensor->name);
  if (!extrinsic)
    throw std::runtime_error("refine: gnss sensor '" + sensor->name +
                             "' has no T_body_sensor (the antenna's lever arm) in mission.yaml "
                             "or /tf_static");
  in.gnss_sensor = sensor->name;
  in.solver.T_body_gnss = *extrinsic;
  const auto& o = *manifest.origin;
  const LocalEnuFrame enu({o.latitude_deg, o.longitude_deg, o.height_m});
  const auto& noise = sensor->noise.gnss;
  const double floor_m2 = options.gnss_min_sigma_m * options.gnss_min_sigma_m;
  for (const io::GnssSample& fix : reader.read_gnss(sensor->name)) {
    if (fix.status < 0) {
      ++in.gnss_no_fix;
      continue;
    }
    slam::GnssFix f;
    f.t_ns = fix.t_ns;
    // A fix without altitude (NaN, NavSatFix's "no altitude") is placed at the origin's height
    // and its vertical variance made uninformative.
    const bool has_height = std::isfinite(fix.height_m);
    f.antenna_world_m =
        enu.to_enu({fix.latitude_deg, fix.longitude_deg, has_height ? fix.height_m : o.height_m});
    if (fix.covariance_known) {
      f.covariance_m2 = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(
          fix.covariance_enu_m2.data());
      f.covariance_m2 = 0.5 * (f.covariance_m2 + f.covariance_m2.transpose()).eval();
    } else {
      f.covariance_m2 = Eigen::Vector3d(noise.horizontal_sigma_m * noise.horizontal_sigma_m,
                                        noise.horizontal_sigma_m * noise.horizontal_sigma_m,
                                        noise.vertical_sigma_m * noise.vertical_sigma_m)
                            .asDiagonal();
    }
    for (int i = 0; i < 3; ++i) f.covariance_m2(i, i) = std::max(f.covariance_m2(i, i), floor_m2);
    if (!has_height) f.covariance_m2(2, 2) = 1e6;
    in.solver.gnss.push_back(f);
  }
  in.report["gnss"] = {
      {"sensor", sensor->name}, {"fixes", in.solver.gnss.size()}, {"no_fix", in.gnss_no_fix}};
}

nlohmann::json gnss_report_json(const slam::RefineResult& result, const Inputs& in,
                                const RefineStageOptions& options,
                                const proto::MissionManifest& manifest) {
  if (in.gnss_sensor.empty()) return nullptr;
  nlohmann::json rejected_t = nlohmann::json::array();
  for (size_t f = 0; f < result.gnss_use.size(); ++f)
    if (result.gnss_use[f] == slam::GnssFixUse::kRejected)
      rejected_t.push_back(ns_to_seconds(in.solver.gnss[f].t_ns));
  nlohmann::json origin = manifest.origin->to_json();
  origin["frame"] = "ENU";
  return {{"sensor", in.gnss_sensor},
          {"used", result.gnss_counts.used},
          {"rejected", result.gnss_counts.rejected},
          {"no_fix", in.gnss_no_fix},
          {"outside_keyframes", result.gnss_counts.outside},
          {"gate_chi2", options.gnss_gate_chi2},
          {"rejected_t_s", rejected_t},
          {"origin", origin}};
}

}  // namespace keel::pipeline
