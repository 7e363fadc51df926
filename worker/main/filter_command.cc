// `keel-worker filter --in FILE.pcd|.ply --out FILE.pcd|.ply --chain JSON_OR_FILE
//  [--threads 2] [--json]`: applies a filter chain of seed 000 Table III (the JSON the `map`
// stage takes in its *_filters options, docs/map-filters.md) to one point cloud file and
// prints the point counts in and out of every filter (--json: and the seconds spent reading,
// filtering and writing).
// Exit codes: 0 done, 1 usage or unreadable input.
#include <nlohmann/json.hpp>

#include <chrono>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>

#include "worker/io/cloud/scan_file.h"
#include "worker/main/commands.h"
#include "worker/mapping/filter_chain.h"

namespace keel::worker {

namespace {

struct FilterArgs {
  std::string in;
  std::string out;
  std::string chain;
  int threads = 2;
  bool json = false;
};

const char* kChainHelp =
    R"(Filter chain (--chain): a JSON array, inline or in a file, applied in order:
  {"type": "crop_box", "min": [x,y,z], "max": [x,y,z], "remove": "outside"|"inside"}
      keep the box's content ("outside", the default) or cut it out ("inside"); min/max required
  {"type": "voxel_grid", "leaf": 0.05}
      one centroid per occupied voxel of `leaf` metres (pcl::VoxelGrid's grid)
  {"type": "ror", "radius": 0.1, "min_neighbors": 5}
      radius outlier removal: keep points with >= min_neighbors others within radius (m)
  {"type": "dror", "beta": 3.0, "alpha_deg": 0.2, "k_min": 4, "sr_min": 0.01}
      dynamic ROR (Charron 2018): radius max(beta * alpha * r_xy, sr_min) grows with the
      horizontal range r_xy from the sensor origin; use it on clouds in the sensor frame
Omitted numbers take these defaults. Example:
  --chain '[{"type":"voxel_grid","leaf":0.02},{"type":"ror","radius":0.05,"min_neighbors":3}]'
See docs/map-filters.md.)";

// The chain as JSON: the text itself when it looks like JSON, else the file it names.
nlohmann::json load_chain(const std::string& text) {
  const size_t first = text.find_first_not_of(" \t\r\n");
  if (first != std::string::npos && (text[first] == '[' || text[first] == '{')) {
    try {
      return nlohmann::json::parse(text);
    } catch (const nlohmann::json::parse_error& e) {
      throw std::invalid_argument("--chain: not valid JSON: " + std::string(e.what()));
    }
  }
  std::ifstream file(text);
  if (!file) throw std::invalid_argument("--chain " + text + ": neither JSON nor a readable file");
  std::stringstream buffer;
  buffer << file.rdbuf();
  try {
    return nlohmann::json::parse(buffer.str());
  } catch (const nlohmann::json::parse_error& e) {
    throw std::invalid_argument(text + ": not valid JSON: " + std::string(e.what()));
  }
}

int run_filter(const FilterArgs& args) {
  const mapping::FilterChain chain =
      mapping::filter_chain_from_json(load_chain(args.chain), "--chain");
  // Each phase's wall time for --json, so a benchmark can tell the work from the I/O and
  // the process start-up (tests/bench/peers_bench.py).
  using Clock = std::chrono::steady_clock;
  const auto seconds_since = [](Clock::time_point t0) {
    return std::chrono::duration<double>(Clock::now() - t0).count();
  };
  auto t0 = Clock::now();
  PointCloud cloud = io::read_scan_file(args.in, 0);
  const double read_s = seconds_since(t0);
  const size_t points_in = cloud.size();
  t0 = Clock::now();
  const std::vector<mapping::FilterStep> steps =
      mapping::apply_filter_chain(chain, cloud, args.threads);
  const double filter_s = seconds_since(t0);
  t0 = Clock::now();
  io::write_scan_file(args.out, cloud);
  const double write_s = seconds_since(t0);
  if (args.json) {
    nlohmann::ordered_json out = {{"in", args.in},
                                  {"out", args.out},
                                  {"points_in", points_in},
                                  {"points_out", cloud.size()},
                                  {"read_seconds", read_s},
                                  {"filter_seconds", filter_s},
                                  {"write_seconds", write_s},
                                  {"filters", nlohmann::json::array()}};
    for (const auto& step : steps)
      out["filters"].push_back({{"filter", step.filter},
                                {"points_in", step.points_in},
                                {"points_out", step.points_out}});
    std::cout << out.dump(2) << std::endl;
    return kExitOk;
  }
  for (const auto& step : steps)
    std::cout << step.filter << ": " << step.points_in << " -> " << step.points_out << "\n";
  std::cout << "in " << points_in << " points, out " << cloud.size() << " points (" << args.out
            << ")" << std::endl;
  return kExitOk;
}

}  // namespace

Subcommand add_filter_command(CLI::App& app) {
  auto args = std::make_shared<FilterArgs>();
  CLI::App* cmd = app.add_subcommand(
      "filter", "Apply a map filter chain (crop_box, voxel_grid, ror, dror) to a PCD/PLY file");
  cmd->footer(kChainHelp);
  cmd->add_option("--in", args->in, "Input cloud (.pcd or .ply)")->required();
  cmd->add_option("--out", args->out, "Output cloud (.pcd or .ply, by extension)")->required();
  cmd->add_option("--chain", args->chain, "Filter chain: a JSON array, or a file holding one")
      ->required();
  cmd->add_option("--threads", args->threads, "Threads for neighbour searches")
      ->check(CLI::Range(1, 256));
  cmd->add_flag("--json", args->json, "Print the counts as JSON");
  return {cmd, [args] {
            try {
              return run_filter(*args);
            } catch (const std::exception& e) {
              std::cerr << "keel-worker filter: " << e.what() << "\n";
              return kExitUsage;
            }
          }};
}

}  // namespace keel::worker
