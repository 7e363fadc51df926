#include "worker/stages/compare/compare_maps.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <set>
#include <stdexcept>

#include "worker/compare/c2c_distance.h"
#include "worker/compare/local_registration.h"
#include "worker/compare/nearest_index.h"
#include "worker/compare/point_grid.h"
#include "worker/compare/voxel_moments.h"
#include "core/robust_spread.h"
#include "worker/io/draco/draco_codec.h"
#include "worker/io/cloud/ply_cloud_writer.h"
#include "worker/io/tum.h"
#include "worker/mapping/map_metrics.h"
#include "core/parallel_for.h"
#include "worker/pipeline/draco_sidecar.h"
#include "worker/stages/map/artifacts.h"

namespace keel::pipeline {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::vector<Eigen::Vector3f> load_map(const fs::path& dir, const std::string& map,
                                      const std::string& job) {
  const fs::path path = dir / map_draco_file(map);
  try {
    return io::decode_draco_point_cloud(io::read_draco_file(path), map_draco_file(map)).positions;
  } catch (const std::exception& e) {
    throw std::runtime_error("job " + job + ": " + e.what());
  }
}

// Positions of A's refined trajectory (every 10th pose), towards which the normals face.
std::vector<Eigen::Vector3f> viewpoints(const fs::path& dir) {
  std::vector<Eigen::Vector3f> out;
  const fs::path path = dir / "trajectory_refined.tum";
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return out;
  const Trajectory trajectory = io::read_tum(path);
  for (size_t i = 0; i < trajectory.size(); i += 10)
    out.push_back(trajectory[i].T_world_body.translation().cast<float>());
  return out;
}

json pose_json(const Pose3& T) {
  const Eigen::Quaterniond q(T.linear());
  return {{"translation_m", {T.translation().x(), T.translation().y(), T.translation().z()}},
          {"rotation_xyzw", {q.x(), q.y(), q.z(), q.w()}},
          {"translation_norm_m", T.translation().norm()},
          {"rotation_deg", Eigen::AngleAxisd(T.linear()).angle() * 180.0 / M_PI}};
}

json registration_json(const compare::StableRegistration& r) {
  json out = {{"T_a_b", pose_json(r.T_a_b)},
              {"iterations", r.iterations},
              {"converged", r.converged},
              {"samples", r.samples},
              {"correspondences", r.correspondences},
              {"stable_pairs", r.stable},
              {"stable_fraction", r.correspondences ? double(r.stable) / r.correspondences : 0.0},
              {"stable_band_m", r.band_m},
              {"rms_stable_m", r.rms_stable_m},
              {"conditioning", r.conditioning}};
  return out;
}

// Histogram of the defined changes over [-range, range] with under- and overflow counts.
json change_histogram(const std::vector<compare::CoreChange>& cores, int bins, double range) {
  std::vector<double> area(bins, 0.0);
  std::vector<size_t> count(bins, 0);
  size_t below = 0, above = 0;
  for (const auto& c : cores) {
    if (!c.defined()) continue;
    if (c.distance_m < -range) {
      ++below;
      continue;
    }
    if (c.distance_m >= range) {
      ++above;
      continue;
    }
    const int bin = std::min(bins - 1, int((c.distance_m + range) / (2.0 * range) * bins));
    ++count[bin];
    area[bin] += c.area_m2;
  }
  std::vector<double> edges(bins + 1);
  for (int i = 0; i <= bins; ++i) edges[i] = -range + 2.0 * range * i / bins;
  return {{"edges_m", edges},
          {"core_points", count},
          {"area_m2", area},
          {"below", below},
          {"above", above}};
}

// A value just below the smallest defined one (by 1/1024 of the range, as the map stage's
// per-point metrics): what a point holds where its core point's change is undefined.
float no_data_below(const std::vector<compare::CoreChange>& cores,
                    float compare::CoreChange::*field) {
  float lo = std::numeric_limits<float>::infinity(), hi = -lo;
  for (const auto& c : cores)
    if (c.defined()) lo = std::min(lo, c.*field), hi = std::max(hi, c.*field);
  if (!(lo <= hi)) lo = hi = 0.0f;
  const float span = std::max(hi - lo, std::max(std::fabs(lo), 1.0f) * 1e-6f);
  return lo - span / 1024.0f;
}

// B's points with their change (change_<map>.drc / .ply): each point its core point's change;
// where that is undefined the attribute's no_data (docs/artifacts.md), so a viewer tells
// "unmeasured" from "unchanged".
struct ChangeCloud {
  PointCloud cloud;
  io::PartsAttributes attributes;
};

ChangeCloud change_cloud(const std::vector<compare::CoreChange>& changes,
                         const std::vector<uint32_t>& core_of, const std::vector<float>& c2c,
                         std::vector<Eigen::Vector3f> points) {
  const float m3c2_no_data = no_data_below(changes, &compare::CoreChange::distance_m);
  const float lod_no_data = no_data_below(changes, &compare::CoreChange::lod95_m);
  std::vector<float> m3c2(points.size()), lod(points.size()), significant(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    const compare::CoreChange& c = changes[core_of[i]];
    m3c2[i] = c.defined() ? c.distance_m : m3c2_no_data;
    lod[i] = c.defined() ? c.lod95_m : lod_no_data;
    significant[i] = c.defined() ? (c.significant ? 1.0f : 0.0f) : -1.0f;
  }
  ChangeCloud out;
  out.cloud.xyz = std::move(points);
  out.cloud.frame = "world";
  out.attributes.fields = {{"m3c2_m", std::move(m3c2)},
                           {"lod95_m", std::move(lod)},
                           {"significant", std::move(significant)},
                           {"c2c_m", c2c}};
  out.attributes.fields_no_data = {m3c2_no_data, lod_no_data, std::nanf(""), std::nanf("")};
  return out;
}

// The report's figures of the change: counts, areas, distributions, the change histogram.
json change_figures(const std::vector<compare::CoreChange>& changes, const std::vector<float>& c2c,
                    const CompareStageOptions& options) {
  double defined_area = 0, significant_area = 0, added = 0, removed = 0;
  size_t defined = 0, significant_cores = 0;
  std::vector<float> distances, lods;
  for (const auto& c : changes) {
    if (!c.defined()) continue;
    ++defined;
    defined_area += c.area_m2;
    distances.push_back(c.distance_m);
    lods.push_back(c.lod95_m);
    if (!c.significant) continue;
    ++significant_cores;
    significant_area += c.area_m2;
    (c.distance_m > 0 ? added : removed) += c.area_m2;
  }
  json r;
  r["core_points"] = changes.size();
  r["defined_core_points"] = defined;
  r["significant_core_points"] = significant_cores;
  r["compared_area_m2"] = defined_area;
  r["significant_area_m2"] = significant_area;
  r["significant_fraction"] = defined_area > 0 ? significant_area / defined_area : 0.0;
  r["significant_added_area_m2"] = added;  // change > 0: material towards the sensor
  r["significant_removed_area_m2"] = removed;
  r["m3c2_m"] = mapping::to_json(mapping::summarize(distances, options.histogram_bins));
  r["lod95_m"] = mapping::to_json(mapping::summarize(lods, options.histogram_bins));
  r["c2c_m"] = mapping::to_json(mapping::summarize(c2c, options.histogram_bins));
  r["change_histogram"] =
      change_histogram(changes, options.histogram_bins, options.histogram_range_m);
  return r;
}

}  // namespace

std::vector<std::string> map_names(const fs::path& dir) {
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    const std::string prefix = "map_", suffix = ".drc";
    if (name.size() <= prefix.size() + suffix.size() || name.rfind(prefix, 0) != 0 ||
        name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0)
      continue;
    const std::string map = name.substr(prefix.size(), name.size() - prefix.size() - suffix.size());
    if (map.size() > 8 && map.compare(map.size() - 8, 8, "_preview") == 0) continue;
    out.push_back(map);
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<std::string> maps_to_compare(const std::vector<std::string>& a,
                                         const std::vector<std::string>& b,
                                         const CompareStageOptions& options) {
  auto has = [](const std::vector<std::string>& list, const std::string& name) {
    return std::find(list.begin(), list.end(), name) != list.end();
  };
  if (!options.sensors.empty()) {
    for (const auto& s : options.sensors) {
      if (!has(a, s))
        throw std::runtime_error("options.compare.sensors: job A has no map '" + s + "'");
      if (!has(b, s))
        throw std::runtime_error("options.compare.sensors: job B has no map '" + s + "'");
    }
    return options.sensors;
  }
  if (has(a, kCombinedMapName) && has(b, kCombinedMapName)) return {kCombinedMapName};
  std::vector<std::string> both;
  for (const auto& s : a)
    if (has(b, s)) both.push_back(s);
  return both;
}

json compare_maps(StageContext& context, const CompareStageOptions& options,
                  const std::vector<std::string>& maps, std::vector<std::string>* artifacts) {
  const InputJob& job_a = context.input_jobs.at(0);
  const InputJob& job_b = context.input_jobs.at(1);
  const std::string id_a = job_a.job.value("id", "A"), id_b = job_b.job.value("id", "B");
  json report = json::object();
  const std::vector<Eigen::Vector3f> views = viewpoints(job_a.dir);
  report["normals_face"] =
      views.empty() ? "+z (job A has no trajectory_refined.tum)" : "job A's refined trajectory";
  Pose3 T_a_b = Pose3::Identity();
  double reg = std::max(0.0, options.registration_error_m);  // per map when < 0
  bool registered = false;

  for (size_t m = 0; m < maps.size(); ++m) {
    const std::string& map = maps[m];
    auto progress = [&](double within) {
      context.progress(0.05 + 0.9 * (m + within) / maps.size());
    };
    json r = json::object();
    json seconds = json::object();
    auto t = std::chrono::steady_clock::now();
    // Two Draco decodes, each single-threaded: side by side.
    std::vector<Eigen::Vector3f> a, b;
    keel::parallel_for_each(2, options.threads, [&](size_t k) {
      if (k == 0) a = load_map(job_a.dir, map, id_a);
      if (k == 1) b = load_map(job_b.dir, map, id_b);
    });
    seconds["load"] = seconds_since(t);
    context.check_canceled();

    // Registration, once, on the first map compared. The same map on both sides (a job
    // compared with itself) is its own registration: the identity, no residual.
    if (options.register_maps && !registered && a == b) {
      report["registration"] = {{"map", map},
                                {"identical_maps", true},
                                {"T_a_b", pose_json(Pose3::Identity())},
                                {"rms_stable_m", 0.0}};
      registered = true;
    }
    if (options.register_maps && !registered) {
      t = std::chrono::steady_clock::now();
      compare::StableRegistrationOptions ro = options.registration;
      ro.threads = options.threads;
      ro.check_canceled = [&] { context.check_canceled(); };
      const compare::StableRegistration result =
          compare::register_stable(a, b, Pose3::Identity(), ro);
      T_a_b = result.T_a_b;
      json rj = registration_json(result);
      rj["map"] = map;
      rj["seconds"] = seconds_since(t);
      report["registration"] = rj;
      registered = true;
      context.log("registered B onto A on " + map + ": " +
                  std::to_string(result.T_a_b.translation().norm()) + " m, rms " +
                  std::to_string(result.rms_stable_m) + " m on " + std::to_string(result.stable) +
                  " stable pairs");
    }
    if (registered)
      for (auto& p : b) p = (T_a_b * p.cast<double>()).cast<float>();
    if (options.register_maps && options.local_registration_tile_m > 0 && !(a == b)) {
      t = std::chrono::steady_clock::now();
      compare::LocalRegistrationOptions lo;
      lo.tile_m = options.local_registration_tile_m;
      lo.margin_m = std::min(1.0, lo.tile_m);
      lo.registration = options.registration;
      lo.registration.threads = options.threads;
      const compare::LocalRegistration local = compare::register_tiles(a, &b, lo);
      const RobustSpread shift = robust_spread(local.correction_m);
      r["local_registration"] = {{"tile_m", lo.tile_m},
                                 {"tiles", local.tiles},
                                 {"adjusted_tiles", local.adjusted},
                                 {"median_correction_m", shift.median},
                                 {"seconds", seconds_since(t)}};
      context.log(map + ": " + std::to_string(local.adjusted) + " of " +
                  std::to_string(local.tiles) + " tiles registered on their own");
    }
    progress(0.2);

    t = std::chrono::steady_clock::now();
    // Grids of cells half the cylinders' diameter: a cylinder at the short depth reads ~10
    // cells of each map, and C2C a point's own cell and the few its distance reaches.
    const double cell = 0.5 * options.m3c2.projection_scale_m;
    const double normal_voxel = options.m3c2.normal_scale_m / 4.0;
    std::unique_ptr<compare::PointGrid> grid_a, grid_b;
    compare::VoxelMoments normals_a, normals_b, cores;
    // Five indexes, each mostly one radix sort (single-threaded): side by side, largest first.
    keel::parallel_for_each(5, options.threads, [&](size_t k) {
      if (k == 0) grid_a = std::make_unique<compare::PointGrid>(a, cell);
      if (k == 1) grid_b = std::make_unique<compare::PointGrid>(b, cell);
      if (k == 2) cores = compare::voxelize(b, options.m3c2.core_spacing_m, true);
      if (k == 3) normals_a = compare::voxelize(a, normal_voxel);
      if (k == 4) normals_b = compare::voxelize(b, normal_voxel);
    });
    seconds["index"] = seconds_since(t);
    context.check_canceled();
    progress(0.35);

    t = std::chrono::steady_clock::now();
    const std::vector<float> c2c = compare::c2c_distances(*grid_a, *grid_b, options.threads);
    seconds["c2c"] = seconds_since(t);
    context.check_canceled();
    progress(0.5);

    t = std::chrono::steady_clock::now();
    compare::M3c2Options mo = options.m3c2;
    mo.registration_error_m = reg;
    mo.threads = options.threads;
    mo.check_canceled = [&] { context.check_canceled(); };
    std::vector<compare::CoreChange> changes =
        compare::m3c2({nullptr, nullptr, &normals_a, &normals_b, grid_a.get(), grid_b.get()},
                      cores.means, views, mo);
    if (options.registration_error_m < 0) {
      // reg from the spread of the change itself (see CompareStageOptions).
      std::vector<double> d;
      for (const auto& c : changes)
        if (c.defined()) d.push_back(c.distance_m);
      std::vector<double> deviation;
      for (double x : d) deviation.push_back(std::abs(x));
      reg = 1.4826 * median_of(deviation);
      compare::apply_registration_error(&changes, reg, mo.confidence_z);
    }
    seconds["m3c2"] = seconds_since(t);
    progress(0.8);

    t = std::chrono::steady_clock::now();
    const size_t points_b = b.size();
    ChangeCloud change = change_cloud(changes, cores.voxel_of, c2c, std::move(b));
    io::DracoOptions draco;
    draco.position_bits = options.draco_position_bits;
    draco.field_bits = options.draco_field_bits;
    draco.compression_level = options.draco_compression_level;
    io::DracoEncoded encoded;
    // The Draco encoding is single-threaded and the longest: the PLY file and the figures are
    // made beside it.
    keel::parallel_for_each(3, options.threads, [&](size_t k) {
      if (k == 0) encoded = io::encode_draco_point_cloud({&change.cloud}, draco, change.attributes);
      if (k == 1 && options.write_ply)
        io::write_ply_cloud(context.work_dir / change_ply_file(map), change.cloud,
                            change.attributes.fields);
      if (k == 2) r.update(change_figures(changes, c2c, options));
    });
    io::write_draco_file(context.work_dir / change_draco_file(map), encoded.bytes);
    artifacts->push_back(change_draco_file(map));
    // The viewer finds the attributes and their ranges here (A's world frame).
    artifacts->push_back(
        write_draco_sidecar(context.work_dir, change_draco_file(map), encoded.summary, "world"));
    if (options.write_ply) artifacts->push_back(change_ply_file(map));
    seconds["write"] = seconds_since(t);

    r["points_a"] = a.size();
    r["points_b"] = points_b;
    r["registration_error_m"] = reg;
    r["draco"] = {{"file", change_draco_file(map)},
                  {"bytes", encoded.bytes.size()},
                  {"max_position_error_m", encoded.max_position_error_m}};
    r["seconds"] = seconds;
    double total = 0;
    for (const auto& [k, v] : seconds.items()) total += v.get<double>();
    r["points_per_second"] = total > 0 ? double(a.size() + points_b) / total : 0.0;
    report["maps"][map] = r;
    progress(1.0);
  }
  report["options"] = {{"normal_scale_m", options.m3c2.normal_scale_m},
                       {"projection_scale_m", options.m3c2.projection_scale_m},
                       {"max_depth_m", options.m3c2.max_depth_m},
                       {"core_spacing_m", options.m3c2.core_spacing_m},
                       {"min_points", options.m3c2.min_points},
                       {"confidence_z", options.m3c2.confidence_z},
                       {"registration_error_m", options.registration_error_m},
                       {"local_registration_tile_m", options.local_registration_tile_m}};
  return report;
}

}  // namespace keel::pipeline
