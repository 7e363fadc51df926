#include "worker/stages/ba/report_json.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/robust_spread.h"
#include "worker/io/yaml_json.h"
#include "worker/pipeline/pose_json.h"

namespace keel::pipeline {

namespace {

using nlohmann::json;

// p-th percentile (0-100) of ascending `sorted`, linear between ranks.
double percentile_of(const std::vector<double>& sorted, double p) {
  const double pos = p / 100.0 * (sorted.size() - 1);
  const size_t lo = size_t(std::floor(pos));
  const size_t hi = std::min(lo + 1, sorted.size() - 1);
  return sorted[lo] + (pos - lo) * (sorted[hi] - sorted[lo]);
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

}  // namespace

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

std::optional<Pose3> truth_T_world_cad(const io::Mission& mission) {
  if (mission.ground_truth_path.empty()) return std::nullopt;
  const json truth = io::load_yaml_file(mission.ground_truth_path);
  if (!truth.contains("T_world_cad")) return std::nullopt;
  return pose_from_json(truth["T_world_cad"], mission.ground_truth_path.string() + ": T_world_cad");
}

json model_error(const Pose3& estimate, const Pose3& truth) {
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

json input_report(const BaKeyframes& keyframes, const BaSensors& sensors, bool frontend_tracks,
                  const std::filesystem::path& cad_mesh) {
  json r = keyframes.report;
  r["tracks_source"] = frontend_tracks ? "frontend (SIFT on the images, Sec. 2.7)"
                                       : "ground_truth (truth.yaml feature_tracks)";
  r["camera"] = sensors.camera->name;
  r["dvl_ranges"] = sensors.dvl->name;
  r["servo"] = sensors.servo->name;
  r["cad_mesh"] = cad_mesh.filename().string();
  return r;
}

json ba_report(json input, const ba::BaResult& result, const ba::BaModeResult& artifact_mode,
               const json& cad_model, const std::optional<Pose3>& truth,
               const BaStageOptions& options) {
  json r;
  r["input"] = std::move(input);
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
  r["observations_dropped_after_initialisation"] = result.observations_dropped_after_initialisation;
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
  r["solution_mode"] = ba::to_string(artifact_mode.mode);
  r["cad_model"] = cad_model;
  return r;
}

}  // namespace keel::pipeline
