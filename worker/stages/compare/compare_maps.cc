#include "worker/stages/compare/compare_maps.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <memory>
#include <stdexcept>

#include "core/parallel_for.h"
#include "core/robust_spread.h"
#include "worker/compare/c2c_distance.h"
#include "worker/compare/coherent_change.h"
#include "worker/compare/local_registration.h"
#include "worker/compare/point_grid.h"
#include "worker/compare/voxel_moments.h"
#include "worker/io/cloud/ply_cloud_writer.h"
#include "worker/io/draco/draco_codec.h"
#include "worker/io/tum.h"
#include "worker/pipeline/draco_sidecar.h"
#include "worker/stages/compare/artifacts.h"
#include "worker/stages/map/artifacts.h"

namespace keel::pipeline {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
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

// The change of B against A: C2C of every point of B, M3C2 at B's core points.
struct MeasuredChange {
  std::vector<float> c2c;
  std::vector<compare::CoreChange> changes;
  std::vector<uint32_t> core_of;  // each point of B's core point
  std::vector<double> reg_m;      // each core's reg; empty: one for all
  std::vector<compare::TileError> tiles;
  std::vector<char> stable;  // each core on its tile's stable structure; empty: unknown
};

// Eq. (1)'s `reg` of every core point from the stable structure of its tile (and, where a
// tile has too little, of the whole map: `reg`), and the level of detection's exceedance on
// that stable structure (compare/local_registration.h tile_registration_errors).
void registration_errors(const CompareStageOptions& options, MeasuredChange* measured,
                         double* reg) {
  std::vector<compare::CoreSample> all;
  for (const auto& c : measured->changes)
    if (c.defined())
      all.push_back({c.position.cast<double>(), c.normal.cast<double>(), double(c.distance_m),
                     double(c.statistical_m)});
  // Each confidence's reg, per tile.
  auto per_core = [&](double z, std::vector<compare::TileError>* tiles, std::vector<char>* stable) {
    const double whole =
        std::max(0.0, compare::tile_registration_error(all, z, options.tile_correction));
    if (options.local_registration_tile_m <= 0)
      return std::vector<double>(measured->changes.size(), whole);
    return compare::tile_registration_errors(measured->changes, options.local_registration_tile_m,
                                             whole, z, options.tile_correction, options.threads,
                                             tiles, stable);
  };
  const double z = options.m3c2.confidence_z;
  *reg = std::max(0.0, compare::tile_registration_error(all, z, options.tile_correction));
  measured->reg_m = per_core(z, &measured->tiles, &measured->stable);
  const std::vector<double> significance_reg = per_core(options.significance_z, nullptr, nullptr);
  compare::apply_registration_errors(&measured->changes, measured->reg_m, z, significance_reg,
                                     options.significance_z);
}

// `reg`: the registration error of Eq. (1); with options.registration_error_m < 0 it is set
// per tile from this map's change (see CompareStageOptions), `reg` the whole map's.
MeasuredChange measure_change(StageContext& context, const CompareStageOptions& options,
                              const std::vector<Eigen::Vector3f>& a,
                              const std::vector<Eigen::Vector3f>& b,
                              const std::vector<Eigen::Vector3f>& views, double* reg, json* seconds,
                              const std::function<void(double)>& progress) {
  auto t = Clock::now();
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
  (*seconds)["index"] = seconds_since(t);
  context.check_canceled();
  progress(0.35);

  MeasuredChange out;
  t = Clock::now();
  out.c2c = compare::c2c_distances(*grid_a, *grid_b, options.threads);
  (*seconds)["c2c"] = seconds_since(t);
  context.check_canceled();
  progress(0.5);

  t = Clock::now();
  compare::M3c2Options mo = options.m3c2;
  mo.registration_error_m = *reg;
  mo.threads = options.threads;
  mo.check_canceled = [&] { context.check_canceled(); };
  out.changes =
      compare::m3c2({nullptr, nullptr, &normals_a, &normals_b, grid_a.get(), grid_b.get()},
                    cores.means, views, mo);
  if (options.registration_error_m < 0) {
    registration_errors(options, &out, reg);
  } else {
    const std::vector<double> given(out.changes.size(), *reg);
    compare::apply_registration_errors(&out.changes, given, mo.confidence_z, given,
                                       options.significance_z);
  }
  compare::require_coherent_change(&out.changes, options.significance_radius_m, options.threads);
  (*seconds)["m3c2"] = seconds_since(t);
  out.core_of = std::move(cores.voxel_of);
  return out;
}

// change_<map>.drc (+ its sidecar, A's world frame) and change_<map>.ply; the figures are made
// beside the Draco encoding, which is single-threaded and the longest. Returns the map's
// figures with its "draco" entry.
json write_change(StageContext& context, const CompareStageOptions& options, const std::string& map,
                  const MeasuredChange& measured, std::vector<Eigen::Vector3f> b,
                  std::vector<std::string>* artifacts) {
  const ChangeCloud change =
      change_cloud(measured.changes, measured.core_of, measured.c2c, std::move(b));
  io::DracoOptions draco;
  draco.position_bits = options.draco_position_bits;
  draco.field_bits = options.draco_field_bits;
  draco.compression_level = options.draco_compression_level;
  io::DracoEncoded encoded;
  json figures;
  keel::parallel_for_each(3, options.threads, [&](size_t k) {
    if (k == 0) encoded = io::encode_draco_point_cloud({&change.cloud}, draco, change.attributes);
    if (k == 1 && options.write_ply)
      io::write_ply_cloud(context.work_dir / change_ply_file(map), change.cloud,
                          change.attributes.fields);
    if (k == 2) figures = change_figures(measured.changes, measured.c2c, options);
  });
  io::write_draco_file(context.work_dir / change_draco_file(map), encoded.bytes);
  artifacts->push_back(change_draco_file(map));
  // The viewer finds the attributes and their ranges here.
  artifacts->push_back(
      write_draco_sidecar(context.work_dir, change_draco_file(map), encoded.summary, "world"));
  if (options.write_ply) artifacts->push_back(change_ply_file(map));
  figures["draco"] = {{"file", change_draco_file(map)},
                      {"bytes", encoded.bytes.size()},
                      {"max_position_error_m", encoded.max_position_error_m}};
  return figures;
}

}  // namespace

json compare_maps(StageContext& context, const CompareStageOptions& options,
                  const std::vector<std::string>& maps, std::vector<std::string>* artifacts) {
  const InputJob& job_a = context.input_jobs.at(0);
  const InputJob& job_b = context.input_jobs.at(1);
  const std::string id_a = job_a.job.value("id", "A"), id_b = job_b.job.value("id", "B");
  json report = json::object();
  const std::vector<Eigen::Vector3f> views = viewpoints(job_a.dir);
  report["normals_face"] =
      views.empty() ? "+z (job A has no trajectory_refined.tum)" : "job A's refined trajectory";
  MapAlignment alignment;
  double reg = std::max(0.0, options.registration_error_m);  // per map when < 0

  for (size_t m = 0; m < maps.size(); ++m) {
    const std::string& map = maps[m];
    auto progress = [&](double within) {
      context.progress(0.05 + 0.9 * (m + within) / maps.size());
    };
    json seconds = json::object();
    auto t = Clock::now();
    // Two Draco decodes, each single-threaded: side by side.
    std::vector<Eigen::Vector3f> a, b;
    keel::parallel_for_each(2, options.threads, [&](size_t k) {
      if (k == 0) a = load_map(job_a.dir, map, id_a);
      if (k == 1) b = load_map(job_b.dir, map, id_b);
    });
    seconds["load"] = seconds_since(t);
    context.check_canceled();

    const json local = align_map(context, options, map, a, &b, &alignment);
    if (alignment.registered) report["registration"] = alignment.registration;
    progress(0.2);

    const MeasuredChange measured =
        measure_change(context, options, a, b, views, &reg, &seconds, progress);
    progress(0.8);

    t = Clock::now();
    const size_t points_b = b.size();
    json r = write_change(context, options, map, measured, std::move(b), artifacts);
    seconds["write"] = seconds_since(t);
    if (!local.is_null()) r["local_registration"] = local;
    r["points_a"] = a.size();
    r["points_b"] = points_b;
    r["registration_error_m"] = reg;
    r["level_of_detection"] = level_of_detection(measured.changes, measured.stable, measured.reg_m,
                                                 measured.tiles, options);
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
                       {"significance_radius_m", options.significance_radius_m},
                       {"significance_z", options.significance_z},
                       {"local_registration_tile_m", options.local_registration_tile_m}};
  return report;
}

}  // namespace keel::pipeline
