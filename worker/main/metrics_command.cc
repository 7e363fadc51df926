// `keel-worker metrics --in FILE.pcd|.ply [--radius 0.25] [--out per_point.ply|.txt]
//  [--max-points N] [--threads 2] [--json]`: the map metrics of seed 000 Table V per point,
// surface density N / (pi r^2) (Eq. (23)), roughness (Eq. (24)) and planarity
// (l2 - l3) / l1 (Eqs. (25)-(26)), over the points within --radius of each point, and their
// means (NaN where a metric is undefined: too few neighbours). --out writes them per point:
// a PLY with scalar fields density, roughness, planarity, or ASCII columns
// `x y z density roughness planarity`.
// Exit codes: 0 done, 1 usage or unreadable input.
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

#include "worker/io/cloud/ply_cloud_writer.h"
#include "worker/io/cloud/scan_file.h"
#include "worker/main/commands.h"
#include "worker/mapping/map_metrics.h"

namespace keel::worker {

namespace {

namespace fs = std::filesystem;

struct MetricsArgs {
  std::string in;
  std::string out;
  double radius_m = 0.25;
  size_t max_points = 0;
  int threads = 2;
  bool json = false;
};

std::string lower_extension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext;
}

void write_text_columns(const std::string& path, const std::vector<Eigen::Vector3f>& xyz,
                        const mapping::PointMetrics& m) {
  FILE* file = std::fopen(path.c_str(), "w");
  if (!file)
    throw std::runtime_error(path + ": cannot open for writing (" + std::strerror(errno) + ")");
  std::fprintf(file, "# x y z density roughness planarity\n");
  for (size_t q = 0; q < m.query_index.size(); ++q) {
    const Eigen::Vector3f& p = xyz[m.query_index[q]];
    std::fprintf(file, "%.9g %.9g %.9g %.9g %.9g %.9g\n", p.x(), p.y(), p.z(), m.surface_density[q],
                 m.roughness[q], m.planarity[q]);
  }
  if (std::fclose(file) != 0) throw std::runtime_error(path + ": write failed");
}

void write_per_point(const std::string& path, const std::vector<Eigen::Vector3f>& xyz,
                     const mapping::PointMetrics& m) {
  const std::string ext = lower_extension(path);
  if (ext == ".txt") return write_text_columns(path, xyz, m);
  if (ext != ".ply")
    throw std::invalid_argument("--out " + path + ": expected a .ply or .txt file name");
  PointCloud queries;
  queries.xyz.reserve(m.query_index.size());
  for (const size_t k : m.query_index) queries.xyz.push_back(xyz[k]);
  io::write_ply_cloud(
      path, queries,
      {{"density", m.surface_density}, {"roughness", m.roughness}, {"planarity", m.planarity}});
}

int run_metrics(const MetricsArgs& args) {
  if (!args.out.empty()) {
    const std::string ext = lower_extension(args.out);
    if (ext != ".ply" && ext != ".txt")
      throw std::invalid_argument("--out " + args.out + ": expected a .ply or .txt file name");
  }
  const PointCloud cloud = io::read_scan_file(args.in, 0);
  mapping::MapMetricsOptions options;
  options.radius_m = args.radius_m;
  options.threads = args.threads;
  options.max_query_points = args.max_points;
  const auto t0 = std::chrono::steady_clock::now();
  const mapping::PointMetrics per_point = mapping::compute_point_metrics(cloud.xyz, options);
  // The computation alone, for --json (benchmarks tell it from I/O and start-up).
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!args.out.empty()) write_per_point(args.out, cloud.xyz, per_point);

  mapping::MapMetrics summary;
  summary.points = cloud.size();
  summary.query_points = per_point.query_index.size();
  summary.radius_m = args.radius_m;
  summary.surface_density = mapping::summarize(per_point.surface_density, options.histogram_bins);
  summary.roughness = mapping::summarize(per_point.roughness, options.histogram_bins);
  summary.planarity = mapping::summarize(per_point.planarity, options.histogram_bins);
  if (args.json) {
    nlohmann::json out = mapping::to_json(summary);
    out["in"] = args.in;
    out["seconds"] = seconds;
    if (!args.out.empty()) out["out"] = args.out;
    std::cout << out.dump(2) << std::endl;
    return kExitOk;
  }
  std::printf("%zu points, %zu query points, radius %g m\n", summary.points, summary.query_points,
              summary.radius_m);
  // A metric defined nowhere (empty cloud, neighbourhoods too small) has no mean: say so
  // rather than print the zeros of an empty distribution.
  const auto line = [](const char* label, const char* unit, const mapping::Distribution& d) {
    if (d.count == 0) {
      std::printf("%s undefined at every query point (%zu)\n", label, d.undefined);
      return;
    }
    std::printf("%s mean %.6g%s (median %.6g, %zu undefined)\n", label, d.mean, unit, d.median,
                d.undefined);
  };
  line("surface density", " points/m^2", summary.surface_density);
  line("roughness      ", " m", summary.roughness);
  line("planarity      ", "", summary.planarity);
  if (!args.out.empty()) std::printf("per-point values: %s\n", args.out.c_str());
  std::fflush(stdout);
  return kExitOk;
}

}  // namespace

Subcommand add_metrics_command(CLI::App& app) {
  auto args = std::make_shared<MetricsArgs>();
  CLI::App* cmd = app.add_subcommand(
      "metrics", "Per-point surface density, roughness and planarity of a PCD/PLY cloud (Table V)");
  cmd->add_option("--in", args->in, "Input cloud (.pcd or .ply)")->required();
  cmd->add_option("--radius", args->radius_m, "Neighbourhood radius in metres (seed 000: 0.25)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--out", args->out,
                  "Per-point values: .ply (scalar fields density, roughness, planarity) or .txt "
                  "(columns x y z density roughness planarity)");
  cmd->add_option("--max-points", args->max_points,
                  "Query at most this many points, evenly strided (0: every point); neighbours "
                  "always come from the whole cloud");
  cmd->add_option("--threads", args->threads, "Threads")->check(CLI::Range(1, 256));
  cmd->add_flag("--json", args->json, "Print the summary (means, percentiles, histograms) as JSON");
  return {cmd, [args] {
            try {
              return run_metrics(*args);
            } catch (const std::exception& e) {
              std::cerr << "keel-worker metrics: " << e.what() << "\n";
              return kExitUsage;
            }
          }};
}

}  // namespace keel::worker
