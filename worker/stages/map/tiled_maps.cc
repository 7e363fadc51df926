#include "worker/stages/map/tiled_maps.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>

#include "core/ordered_parallel.h"
#include "worker/mapping/tiled_filter.h"

namespace keel::pipeline {
namespace {

using mapping::TileKey;

// Output tiles: 1024 units of 1 cm (10.24 m), the same for every map.
constexpr double kOutputUnitM = 0.01;
constexpr int64_t kOutputUnitsPerTile = 1024;
// Grid unit of a chain without a voxel grid.
constexpr double kFilterUnitM = 0.01;
constexpr uint16_t kSlamCloud = 1000;
constexpr uint16_t kOutputCloudBase = 2000;
// Filtered tiles waiting for their turn to be written to the output tiles, per thread.
constexpr size_t kWaitingPerThread = 2;

std::vector<TileKey> sorted_tiles(const std::vector<io::StreamKey>& keys) {
  std::set<TileKey> tiles;
  for (const auto& key : keys) tiles.insert(tile_of_key(key));
  return {tiles.begin(), tiles.end()};
}

}  // namespace

TiledMapsOptions tiled_maps_options_for_budget(double budget_bytes, int threads,
                                               double output_halo_m) {
  TiledMapsOptions options;
  options.buffer_budget_bytes = static_cast<size_t>(budget_bytes * kSpillShare);
  options.tile_budget_bytes = static_cast<size_t>(budget_bytes * kTileShare / std::max(1, threads));
  options.threads = threads;
  options.output_halo_m = output_halo_m;
  return options;
}

struct TiledMaps::Sensor {
  std::string name;
  uint16_t input_cloud = 0, output_cloud = 0;
  mapping::FilterChain chain;
  mapping::TileGrid grid;
  HaloFunction halo;
  bool has_halo = false;
  std::unique_ptr<TileBinner> input, output;
  bool input_intensity = true;
  size_t output_points = 0;
  TiledFilterStats stats;

  Sensor(std::string n, mapping::FilterChain c, double tile_edge_m)
      : name(std::move(n)), chain(std::move(c)), grid(grid_for(chain, tile_edge_m)) {
    halo = [this](const mapping::Box& box) { return mapping::chain_halo_m(chain, grid, box); };
    has_halo = halo(grid.box(TileKey{})) > 0.0;
  }

  // Tiles at least 4 halos wide (near the origin), so that a point is copied into a few halos
  // at most rather than into every tile within a wide neighbourhood's reach.
  static mapping::TileGrid grid_for(const mapping::FilterChain& chain, double tile_edge_m) {
    const double unit = mapping::tile_unit_for(chain, kFilterUnitM);
    const mapping::TileGrid first = mapping::TileGrid::with_edge_near(unit, tile_edge_m);
    const double halo = mapping::chain_halo_m(chain, first, first.box(TileKey{}));
    if (halo * 4 <= first.edge_m()) return first;
    return mapping::TileGrid::with_edge_near(unit, 8 * halo);
  }
};

TiledMaps::TiledMaps(const std::filesystem::path& spill_folder,
                     const std::vector<std::pair<std::string, mapping::FilterChain>>& sensors,
                     TiledMapsOptions options)
    : options_(options),
      store_(std::make_unique<io::SpillStore>(spill_folder, options.buffer_budget_bytes)),
      output_grid_(kOutputUnitM, kOutputUnitsPerTile) {
  const double output_halo =
      options_.output_halo_m > 0.0 ? options_.output_halo_m + mapping::kHaloMarginM : 0.0;
  output_halo_ = [output_halo](const mapping::Box&) { return output_halo; };
  for (const auto& [name, chain] : sensors) {
    auto s = std::make_unique<Sensor>(name, chain, options_.filter_tile_edge_m);
    s->input_cloud = static_cast<uint16_t>(1 + sensors_.size());
    s->output_cloud = static_cast<uint16_t>(kOutputCloudBase + sensors_.size());
    s->input = std::make_unique<TileBinner>(*store_, s->input_cloud, s->grid, s->halo, s->has_halo);
    s->output = std::make_unique<TileBinner>(*store_, s->output_cloud, output_grid_, output_halo_,
                                             output_halo > 0.0);
    sensors_.push_back(std::move(s));
  }
  slam_binner_ = std::make_unique<TileBinner>(*store_, kSlamCloud, output_grid_, output_halo_,
                                              output_halo > 0.0);
}

TiledMaps::~TiledMaps() = default;

TiledMaps::Sensor& TiledMaps::sensor(const std::string& name) {
  for (auto& s : sensors_)
    if (s->name == name) return *s;
  throw std::invalid_argument("tiled maps: no sensor '" + name + "'");
}

const TiledMaps::Sensor& TiledMaps::sensor(const std::string& name) const {
  for (const auto& s : sensors_)
    if (s->name == name) return *s;
  throw std::invalid_argument("tiled maps: no sensor '" + name + "'");
}

uint16_t TiledMaps::output_cloud(const std::string& map) const {
  return map == "slam" ? kSlamCloud : sensor(map).output_cloud;
}

void TiledMaps::add_final_input(const std::string& name, const PointCloud& points) {
  Sensor& s = sensor(name);
  if (points.empty()) return;
  s.input_intensity = s.input_intensity && points.intensity.size() == points.size();
  s.stats.points_in += points.size();
  s.input->add(points);
}

void TiledMaps::split_filter_tiles(Sensor& s, std::vector<TileKey>& tiles) {
  std::vector<TileKey> fitting;
  std::vector<TileKey> todo(tiles.rbegin(), tiles.rend());  // a stack, first tile on top
  while (!todo.empty()) {
    const TileKey tile = todo.back();
    todo.pop_back();
    const uint64_t points = (store_->size(stream_key(s.input_cloud, TileStream::kCore, tile)) +
                             store_->size(stream_key(s.input_cloud, TileStream::kHalo, tile))) /
                            sizeof(PointRecord);
    const double bytes = static_cast<double>(points) * kFilterBytesPerPoint;
    if (bytes <= static_cast<double>(options_.tile_budget_bytes)) {
      fitting.push_back(tile);
      continue;
    }
    // Halves that would be narrower than the halo only move points into halos.
    const int child_level = tile.level + 1;
    const bool can_split =
        child_level <= s.grid.max_level() && s.grid.edge_m(child_level) >= s.halo(s.grid.box(tile));
    if (!can_split)
      throw TileBudgetError(
          "map: sensor '" + s.name + "': filter tile " + tile.to_string() + " (" +
              std::to_string(s.grid.edge_m(tile.level)) + " m, the smallest the filters allow) " +
              "holds " + std::to_string(points) + " points with its halo and needs " +
              std::to_string(static_cast<long long>(std::ceil(bytes / (1 << 20)))) +
              " MiB to filter",
          bytes);
    std::vector<TileKey> children =
        split_tile(*store_, {s.input_cloud}, s.grid, tile, s.halo, s.has_halo, true);
    ++s.stats.splits;
    std::sort(children.begin(), children.end());
    todo.insert(todo.end(), children.rbegin(), children.rend());
  }
  tiles = std::move(fitting);
}

void TiledMaps::filter_sensor(const std::string& name,
                              const std::function<void()>& check_canceled) {
  Sensor& s = sensor(name);
  s.input->flush();
  std::vector<TileKey> tiles = sorted_tiles(store_->keys(s.input_cloud, 0));
  split_filter_tiles(s, tiles);
  struct Filtered {
    PointCloud points;
    std::vector<mapping::FilterStep> steps;
    size_t halo_points = 0, tile_points = 0;
  };
  const auto produce = [&](size_t index) {
    if (check_canceled) check_canceled();
    const TileKey& tile = tiles[index];
    const io::StreamKey core_key = stream_key(s.input_cloud, TileStream::kCore, tile);
    const io::StreamKey halo_key = stream_key(s.input_cloud, TileStream::kHalo, tile);
    mapping::TileWork work;
    work.points.frame = "world";
    {
      const std::vector<PointRecord> core = read_records(*store_, core_key);
      append_records(core, s.input_intensity, work.points);
      work.owned.assign(core.size(), 1);
    }
    store_->erase(core_key);
    Filtered out;
    {
      const std::vector<PointRecord> halo = read_records(*store_, halo_key);
      append_records(halo, s.input_intensity, work.points);
      work.owned.resize(work.points.size(), 0);
      out.halo_points = halo.size();
    }
    store_->erase(halo_key);
    out.tile_points = work.points.size();
    out.steps = mapping::filter_tile(s.chain, s.grid, tile, work, 1);
    out.points = std::move(work.points);
    return out;
  };
  const auto consume = [&](size_t, Filtered filtered) {
    ++s.stats.tiles;
    s.stats.halo_points += filtered.halo_points;
    s.stats.largest_tile_points = std::max(s.stats.largest_tile_points, filtered.tile_points);
    if (s.stats.steps.empty()) {
      s.stats.steps = filtered.steps;
    } else {
      for (size_t k = 0; k < filtered.steps.size(); ++k) {
        s.stats.steps[k].points_in += filtered.steps[k].points_in;
        s.stats.steps[k].points_out += filtered.steps[k].points_out;
      }
    }
    s.output_points += filtered.points.size();
    s.output->add(filtered.points);
  };
  ordered_parallel<Filtered>(tiles.size(), options_.threads,
                             kWaitingPerThread * static_cast<size_t>(options_.threads), produce,
                             consume);
  s.output->flush();
}

const TiledFilterStats& TiledMaps::filter_stats(const std::string& name) const {
  return sensor(name).stats;
}

void TiledMaps::add_slam_points(const PointCloud& points) {
  if (points.empty()) return;
  slam_intensity_ = slam_intensity_ && points.intensity.size() == points.size();
  slam_points_ += points.size();
  slam_binner_->add(points);
}

void TiledMaps::finish_slam() { slam_binner_->flush(); }

size_t TiledMaps::points(const std::string& map) const {
  return map == "slam" ? slam_points_ : sensor(map).output_points;
}

bool TiledMaps::has_intensity(const std::string& map) const {
  return map == "slam" ? slam_intensity_ && slam_points_ > 0
                       : sensor(map).input_intensity && sensor(map).output_points > 0;
}

PointCloud TiledMaps::load(const std::string& map, const TileKey& tile, bool with_halo,
                           size_t* owned) const {
  const uint16_t cloud = output_cloud(map);
  const bool intensity = has_intensity(map);
  PointCloud out;
  out.frame = "world";
  append_records(read_records(*store_, stream_key(cloud, TileStream::kCore, tile)), intensity, out);
  if (owned) *owned = out.size();
  if (with_halo)
    append_records(read_records(*store_, stream_key(cloud, TileStream::kHalo, tile)), intensity,
                   out);
  return out;
}

uint64_t TiledMaps::tile_points(const std::vector<std::string>& maps, const TileKey& tile,
                                bool with_halo) const {
  uint64_t bytes = 0;
  for (const auto& map : maps) {
    bytes += store_->size(stream_key(output_cloud(map), TileStream::kCore, tile));
    if (with_halo) bytes += store_->size(stream_key(output_cloud(map), TileStream::kHalo, tile));
  }
  return bytes / sizeof(PointRecord);
}

std::vector<TileKey> TiledMaps::output_partition(const std::vector<std::string>& maps) {
  std::set<TileKey> level0;
  for (const auto& map : maps)
    for (const auto& key : store_->keys(output_cloud(map), 0))
      if (key.level == 0) level0.insert(tile_of_key(key));
  std::lock_guard<std::mutex> lock(split_mutex_);
  std::vector<TileKey> out;
  for (const TileKey& tile : level0) partition_into(maps, tile, out);
  return out;
}

void TiledMaps::partition_into(const std::vector<std::string>& maps, const TileKey& tile,
                               std::vector<TileKey>& out) {
  if (tile_points(maps, tile, false) == 0) return;
  const double points = static_cast<double>(tile_points(maps, tile, true));
  const double bytes = points * kOutputBytesPerPoint;
  if (bytes <= static_cast<double>(options_.tile_budget_bytes)) {
    out.push_back(tile);
    return;
  }
  const bool can_split = tile.level < output_grid_.max_level() &&
                         output_grid_.edge_m(tile.level + 1) >= options_.output_halo_m;
  if (!can_split)
    throw TileBudgetError(
        "map: output tile " + tile.to_string() + " (" +
            std::to_string(output_grid_.edge_m(tile.level)) + " m) holds " +
            std::to_string(static_cast<long long>(points)) + " points with its halo and needs " +
            std::to_string(static_cast<long long>(std::ceil(bytes / (1 << 20)))) + " MiB to read",
        bytes);
  for (const auto& map : maps) {
    const uint16_t cloud = output_cloud(map);
    if (split_.insert({cloud, tile}).second)
      split_tile(*store_, {cloud}, output_grid_, tile, output_halo_,
                 output_halo_(mapping::Box{}) > 0.0, false);
  }
  for (int c = 0; c < 8; ++c) partition_into(maps, output_grid_.child(tile, c), out);
}

void TiledMaps::erase(const std::string& map) {
  const uint16_t cloud = output_cloud(map);
  for (uint8_t kind : {0, 1})
    for (const auto& key : store_->keys(cloud, kind)) store_->erase(key);
}

}  // namespace keel::pipeline
