// The map stage's out-of-core maps (issue 17): points fed as the scans would feed them, final
// filters run tile by tile through a SpillStore whose budget forces spilling and splits, and
// then every output read from the tiles: the maps equal the whole-map chain point for point;
// the streamed PLY is byte for byte the in-memory writer's file of the same map; the tiled
// metrics equal compute_map_metrics on the same map with the same query points; the LOD tileset
// (read with the specification reader) holds every point once; a budget too small for one
// tile is refused with the minimum that would work.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <map>
#include <random>

#include "tests/worker/io/pnts_reader.h"
#include "tests/worker/mapping/test_clouds.h"
#include "worker/io/cloud/ply_cloud_writer.h"
#include "worker/mapping/filter_chain.h"
#include "worker/mapping/map_builder.h"
#include "worker/mapping/map_metrics.h"
#include "worker/stages/map/map_lod.h"
#include "worker/stages/map/tiled_maps.h"
#include "worker/stages/map/tiled_outputs.h"

namespace keel::pipeline {
namespace {

namespace fs = std::filesystem;
using Point = std::array<float, 4>;

fs::path temp_dir(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("keel_tiled_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::vector<Point> sorted_points(const PointCloud& cloud) {
  std::vector<Point> points;
  for (size_t k = 0; k < cloud.size(); ++k)
    points.push_back({cloud.xyz[k].x(), cloud.xyz[k].y(), cloud.xyz[k].z(),
                      cloud.has_intensity() ? cloud.intensity[k] : -1.f});
  std::sort(points.begin(), points.end());
  return points;
}

// A "bridge": two walls and a deck over 60 m x 30 m x 12 m, noisy, sampled in batches the way
// intermediary maps arrive (each batch along a stretch of the path), with outliers.
std::vector<PointCloud> survey_batches(size_t batches, size_t per_batch, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  std::normal_distribution<float> noise(0.f, 0.01f);
  std::vector<PointCloud> out;
  for (size_t b = 0; b < batches; ++b) {
    PointCloud batch;
    batch.frame = "world";
    const float x0 = -10.f + 60.f * static_cast<float>(b) / batches;
    for (size_t k = 0; k < per_batch; ++k) {
      const float x = x0 + 8.f * u(rng), s = u(rng);
      Eigen::Vector3f p;
      switch (k % 4) {
        case 0:
          p = {x, -5.f + noise(rng), 12.f * s};
          break;  // wall
        case 1:
          p = {x, 25.f + noise(rng), 12.f * s};
          break;  // wall
        case 2:
          p = {x, -5.f + 30.f * s, 12.f + noise(rng)};
          break;  // deck
        default:
          p = {x, -5.f + 30.f * s, 12.f * u(rng)};  // sparse outliers
      }
      batch.xyz.push_back(p);
      batch.intensity.push_back(std::floor(100.f * u(rng)));
    }
    out.push_back(std::move(batch));
  }
  return out;
}

struct Fixture {
  std::vector<std::pair<std::string, mapping::FilterChain>> sensors;
  std::map<std::string, std::vector<PointCloud>> input;
  std::map<std::string, PointCloud> whole;  // the chain over the whole map

  Fixture() {
    sensors = {
        {"lidar", mapping::filter_chain_from_json(
                      nlohmann::json::parse(R"([{"type": "voxel_grid", "leaf": 0.05},
                                 {"type": "ror", "radius": 0.12, "min_neighbors": 2}])"),
                      "chain")},
        {"sonar", mapping::filter_chain_from_json(
                      nlohmann::json::parse(R"([{"type": "voxel_grid", "leaf": 0.1}])"), "chain")}};
    input["lidar"] = survey_batches(30, 20000, 1);
    input["sonar"] = survey_batches(12, 10000, 2);
    for (const auto& [name, chain] : sensors) {
      PointCloud all;
      for (const auto& batch : input[name]) {
        all.xyz.insert(all.xyz.end(), batch.xyz.begin(), batch.xyz.end());
        all.intensity.insert(all.intensity.end(), batch.intensity.begin(), batch.intensity.end());
      }
      mapping::apply_filter_chain(chain, all, 2);
      whole[name] = std::move(all);
    }
  }

  std::unique_ptr<TiledMaps> run(const fs::path& dir, TiledMapsOptions options) const {
    auto maps = std::make_unique<TiledMaps>(dir, sensors, options);
    for (const auto& [name, chain] : sensors) {
      for (const auto& batch : input.at(name)) maps->add_final_input(name, batch);
      maps->filter_sensor(name, {});
    }
    maps->finish_slam();
    return maps;
  }
};

TiledMapsOptions small_budget() {
  TiledMapsOptions options;
  options.buffer_budget_bytes = 1 << 20;   // 1 MiB of buffers: almost everything spills
  options.tile_budget_bytes = 12'000'000;  // ~100k points per tile being filtered
  options.filter_tile_edge_m = 20.0;
  options.output_halo_m = 0.25;
  return options;
}

TEST(TiledMaps, FiltersOverSpilledSplitTilesEqualTheWholeMapPointForPoint) {
  const Fixture f;
  const fs::path dir = temp_dir("equal");
  auto maps = f.run(dir, small_budget());
  EXPECT_GT(maps->store().bytes_spilled(), 10u << 20);
  EXPECT_LE(maps->store().peak_bytes_buffered(), (1u << 20) + (1u << 18) * 16);
  for (const auto& [name, chain] : f.sensors) {
    SCOPED_TRACE(name);
    const TiledFilterStats& stats = maps->filter_stats(name);
    EXPECT_GT(stats.tiles, 4u);
    EXPECT_LE(stats.largest_tile_points * kFilterBytesPerPoint, 12'000'000.0);
    const auto tiles = maps->output_partition({name});
    const PointCloud gathered = gather_tiled_map(*maps, {name}, tiles);
    EXPECT_EQ(maps->points(name), f.whole.at(name).size());
    EXPECT_TRUE(sorted_points(gathered) == sorted_points(f.whole.at(name)));
    // The whole map's filter counts.
    PointCloud all;
    for (const auto& batch : f.input.at(name))
      all.xyz.insert(all.xyz.end(), batch.xyz.begin(), batch.xyz.end());
    const auto steps = mapping::apply_filter_chain(chain, all, 2);
    ASSERT_EQ(stats.steps.size(), steps.size());
    for (size_t s = 0; s < steps.size(); ++s) {
      EXPECT_EQ(stats.steps[s].points_in, steps[s].points_in);
      EXPECT_EQ(stats.steps[s].points_out, steps[s].points_out);
    }
  }
  EXPECT_GT(maps->filter_stats("lidar").splits, 0u);  // the budget forced splits
  fs::remove_all(dir);
}

TEST(TiledMaps, StreamedOutputsEqualTheInMemoryOnes) {
  const Fixture f;
  const fs::path dir = temp_dir("outputs");
  TiledMapsOptions options = small_budget();
  options.tile_budget_bytes = 1'600'000;  // output tiles split too (20k points each)
  auto maps = f.run(dir, options);
  const std::vector<std::string> parts = {"lidar", "sonar"};
  const auto tiles = maps->output_partition(parts);
  EXPECT_GT(tiles.size(), 6u);
  EXPECT_TRUE(std::any_of(tiles.begin(), tiles.end(), [](const auto& t) { return t.level > 0; }));
  const PointCloud combined = gather_tiled_map(*maps, parts, tiles);

  // PLY: the same bytes as the in-memory writer's.
  write_tiled_ply(*maps, parts, tiles, dir / "streamed.ply");
  io::write_ply_cloud(dir / "memory.ply", combined);
  EXPECT_TRUE(testing::read_file_bytes(dir / "streamed.ply") ==
              testing::read_file_bytes(dir / "memory.ply"));

  // Metrics: the same query points, every neighbourhood the whole map's.
  mapping::MapMetricsOptions metrics_options;
  metrics_options.max_query_points = 3000;
  const mapping::MapMetrics tiled = tiled_map_metrics(*maps, parts, tiles, metrics_options);
  const mapping::MapMetrics memory = mapping::compute_map_metrics(combined, metrics_options);
  EXPECT_EQ(tiled.points, memory.points);
  EXPECT_EQ(tiled.query_points, 3000u);
  EXPECT_EQ(tiled.surface_density.count, memory.surface_density.count);
  EXPECT_DOUBLE_EQ(tiled.surface_density.mean, memory.surface_density.mean);  // counts: exact
  EXPECT_DOUBLE_EQ(tiled.surface_density.max, memory.surface_density.max);
  EXPECT_EQ(tiled.roughness.count, memory.roughness.count);
  EXPECT_NEAR(tiled.roughness.mean, memory.roughness.mean, 1e-6 * memory.roughness.mean);
  EXPECT_NEAR(tiled.planarity.mean, memory.planarity.mean, 1e-6);
  EXPECT_GT(memory.surface_density.mean, 0.0);

  // LOD tiles: every point of the combined map in exactly one finest tile.
  LodTileSource source{tiles, [&](const mapping::TileKey& tile) {
                         auto points = mapping::LodPoints::with_attributes(2);
                         for (size_t p = 0; p < parts.size(); ++p) {
                           const PointCloud part = maps->load(parts[p], tile);
                           points.xyz.insert(points.xyz.end(), part.xyz.begin(), part.xyz.end());
                           points.attributes[0].insert(points.attributes[0].end(),
                                                       part.intensity.begin(),
                                                       part.intensity.end());
                           points.attributes[1].resize(points.xyz.size(), static_cast<float>(p));
                         }
                         return points;
                       }};
  mapping::LodOptions lod;
  lod.max_points_per_tile = 20000;
  const MapTilesetResult result =
      write_map_tileset(dir / "tiles_combined.tar", maps->output_grid(), source,
                        {{"intensity", io::PntsAttribute::Type::kFloat},
                         {"sensor", io::PntsAttribute::Type::kUnsignedByte}},
                        {{"map", "combined"}}, lod);
  EXPECT_EQ(result.points, combined.size());
  const testing::Tileset tileset = testing::read_tileset_tar(dir / "tiles_combined.tar", dir / "x");
  // Each map point matched by exactly one finest-tile point (within half a quantization step,
  // same intensity and sensor), found through a 1 mm hash grid.
  std::map<std::array<int64_t, 3>, std::vector<size_t>> grid;
  const auto cell = [](const Eigen::Vector3d& p) {
    return std::array<int64_t, 3>{static_cast<int64_t>(std::floor(p.x() * 1000)),
                                  static_cast<int64_t>(std::floor(p.y() * 1000)),
                                  static_cast<int64_t>(std::floor(p.z() * 1000))};
  };
  for (size_t k = 0; k < combined.size(); ++k)
    grid[cell(combined.xyz[k].cast<double>())].push_back(k);
  std::vector<int> matched(combined.size(), 0);
  size_t finest_points = 0;
  for (const auto& [uri, tile] : tileset.tiles) {
    if (!tile.children.empty()) continue;
    const double half_step = tile.box[3] / 65535 + 1e-9;
    for (size_t k = 0; k < tile.content.positions.size(); ++k, ++finest_points) {
      const Eigen::Vector3d& p = tile.content.positions[k];
      const auto c = cell(p);
      bool found = false;
      for (int dx = -1; dx <= 1 && !found; ++dx)
        for (int dy = -1; dy <= 1 && !found; ++dy)
          for (int dz = -1; dz <= 1 && !found; ++dz) {
            const auto it = grid.find({c[0] + dx, c[1] + dy, c[2] + dz});
            if (it == grid.end()) continue;
            for (const size_t m : it->second)
              if (!matched[m] &&
                  (combined.xyz[m].cast<double>() - p).cwiseAbs().maxCoeff() <= half_step &&
                  combined.intensity[m] == tile.content.properties.at("intensity")[k]) {
                matched[m] = 1;
                found = true;
                break;
              }
          }
      EXPECT_TRUE(found) << uri << " point " << k;
    }
  }
  EXPECT_EQ(finest_points, combined.size());
  EXPECT_EQ(std::count(matched.begin(), matched.end(), 1), static_cast<long>(combined.size()));
  fs::remove_all(dir);
}

// The same scans through MapBuilder in memory (its streamed voxel map, the path the map stage
// took before issue 17) and through its final sink into spilled tiles: the same map, bit for bit.
TEST(TiledMaps, MapBuilderInMemoryAndThroughTilesGiveTheSameMap) {
  mapping::TransformTree tree(
      mapping::testing::sample_trajectory(0.0, 40.0, 0.01, {1.5, 0.4, 0.05}, 0.03));
  tree.set_extrinsic("lidar", Pose3::Identity());
  mapping::MapBuilderOptions options;
  options.scans_per_intermediary = 5;
  options.default_sensor.scan_filters = mapping::FilterChain{};
  options.default_sensor.final_filters.filters.push_back(mapping::VoxelGridFilter{0.05});
  options.default_sensor.deskew = false;
  std::vector<PointCloud> scans;
  for (int s = 0; s < 120; ++s) {  // 60 m of path, scans of a 12 m cube around the vehicle
    PointCloud scan = mapping::testing::random_cloud(4000, -6.f, 6.f, static_cast<unsigned>(s));
    scan.t_ns = seconds_to_ns(1.0 + 0.3 * s);
    scans.push_back(std::move(scan));
  }
  mapping::MapBuilder memory(tree, options);
  for (const auto& scan : scans) memory.add_scan("lidar", scan);
  memory.finish();

  const fs::path dir = temp_dir("builder");
  TiledMapsOptions tiled_options = small_budget();
  tiled_options.tile_budget_bytes = 3'000'000;
  TiledMaps tiled(dir, {{"lidar", options.default_sensor.final_filters}}, tiled_options);
  options.final_sink = [&](const std::string& sensor, const PointCloud& points) {
    tiled.add_final_input(sensor, points);
  };
  options.threads = 2;
  mapping::MapBuilder streamed(tree, options);
  size_t next = 0;
  streamed.add_scans([&](std::string& sensor, PointCloud& scan) {
    if (next == scans.size()) return false;
    sensor = "lidar";
    scan = scans[next++];
    return true;
  });
  streamed.finish();
  EXPECT_TRUE(streamed.sensor_map("lidar").empty());
  tiled.filter_sensor("lidar", {});
  EXPECT_GT(tiled.store().bytes_spilled(), 0u);
  EXPECT_GT(tiled.filter_stats("lidar").splits, 0u);
  const PointCloud gathered = gather_tiled_map(tiled, {"lidar"}, tiled.output_partition({"lidar"}));
  ASSERT_GT(gathered.size(), 100000u);
  EXPECT_EQ(gathered.size(), memory.sensor_map("lidar").size());
  EXPECT_TRUE(sorted_points(gathered) == sorted_points(memory.sensor_map("lidar")));
  fs::remove_all(dir);
}

TEST(TiledMaps, ABudgetTooSmallForOneTileIsRefusedWithTheMinimum) {
  // 200,000 points within one 5 cm voxel: no split makes that tile smaller.
  const fs::path dir = temp_dir("refuse");
  TiledMapsOptions options;
  options.buffer_budget_bytes = 1 << 20;
  options.tile_budget_bytes = 1'000'000;
  std::vector<std::pair<std::string, mapping::FilterChain>> sensors = {
      {"lidar", mapping::filter_chain_from_json(
                    nlohmann::json::parse(R"([{"type": "voxel_grid", "leaf": 0.05}])"), "c")}};
  TiledMaps maps(dir, sensors, options);
  PointCloud dense;
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> u(1.01f, 1.04f);
  for (int k = 0; k < 200000; ++k) dense.xyz.emplace_back(u(rng), u(rng), u(rng));
  maps.add_final_input("lidar", dense);
  try {
    maps.filter_sensor("lidar", {});
    FAIL() << "expected a TileBudgetError";
  } catch (const TileBudgetError& e) {
    EXPECT_NEAR(e.minimum_bytes(), 200000 * kFilterBytesPerPoint, 1.0);
    const std::string message = e.what();
    EXPECT_NE(message.find("lidar"), std::string::npos) << message;
    EXPECT_NE(message.find("200000 points"), std::string::npos) << message;
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace keel::pipeline
