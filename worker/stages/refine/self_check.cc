#include "worker/stages/refine/self_check.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <vector>

#include "worker/slam/map_agreement.h"
#include "worker/stages/refine/artifacts.h"
#include "worker/stages/refine/report_json.h"

namespace keel::pipeline {

namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

nlohmann::json self_check_json(const slam::MapAgreement& a) {
  std::vector<TimeNs> t_ns;
  std::vector<bool> flagged;
  for (const auto& m : a.keyframes) {
    t_ns.push_back(m.t_ns);
    flagged.push_back(m.flagged);
  }
  return {{"keyframes", a.keyframes.size()},
          {"flagged_keyframes", a.flagged},
          {"flagged_ranges", stamp_ranges(t_ns, flagged)},
          {"chi2_threshold", a.chi2_threshold},
          {"translation_m", {{"rms", a.translation_rms_m}, {"max", a.translation_max_m}}},
          {"rotation_deg",
           {{"rms", a.rotation_rms_rad * kRadToDeg}, {"max", a.rotation_max_rad * kRadToDeg}}},
          {"per_keyframe", kSelfCheckFile}};
}

void write_self_check_csv(const std::filesystem::path& path, const slam::MapAgreement& a) {
  std::ofstream out(path);
  out << "t_s,dx_m,dy_m,dz_m,moved_m,droll_deg,dpitch_deg,dyaw_deg,turned_deg,drift_path_m,"
         "mahalanobis_translation,mahalanobis_rotation,flagged\n";
  char line[512];
  for (const auto& m : a.keyframes) {
    const Eigen::Vector3d r = m.rotation_rad * kRadToDeg;
    std::snprintf(
        line, sizeof line, "%.9f,%.6f,%.6f,%.6f,%.6f,%.5f,%.5f,%.5f,%.5f,%.3f,%.4f,%.4f,%d\n",
        ns_to_seconds(m.t_ns), m.translation_m.x(), m.translation_m.y(), m.translation_m.z(),
        m.translation_m.norm(), r.x(), r.y(), r.z(), r.norm(), m.drift_path_m,
        m.mahalanobis_translation, m.mahalanobis_rotation, m.flagged ? 1 : 0);
    out << line;
  }
  if (!out) throw std::runtime_error(path.string() + ": could not write the self-check");
}

}  // namespace

nlohmann::json self_check(const Trajectory& map_poses, const Trajectory& refined,
                          const slam::RefineResult& result, const std::filesystem::path& csv_path) {
  std::vector<double> drift_path;
  for (const auto& k : result.keyframes) drift_path.push_back(k.map_drift_path_m);
  const slam::MapAgreement agreement =
      slam::compare_with_map(map_poses, refined, result.map_noise, drift_path);
  write_self_check_csv(csv_path, agreement);
  return self_check_json(agreement);
}

}  // namespace keel::pipeline
