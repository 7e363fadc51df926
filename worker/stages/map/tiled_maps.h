// The map stage's maps out of core (issue 17). What leaves each sensor's intermediary stage goes
// into that sensor's filter tiles on a SpillStore (core and halo streams); once the sensor's
// scans are in, its final filters run tile by tile (mapping::filter_tile: the same points as
// over the whole map) on `threads` threads, and the owned output goes, in tile order, to the
// output tiles: one grid (10.24 m cubes of 1 cm units) shared by every map, so a tile of the
// combined map is the same tile of each sensor map, with halos as wide as the metrics radius.
// The SLAM-map baseline goes straight into the output tiles. Tiles too dense for the memory
// budget are split into 8 (repeatedly) before they are read.
#pragma once

#include <atomic>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "core/point_cloud.h"
#include "worker/io/cloud/spill_store.h"
#include "worker/mapping/filter_chain.h"
#include "worker/mapping/tile_grid.h"
#include "worker/stages/map/tile_streams.h"

namespace keel::pipeline {

// Bytes per point a tile needs while it is filtered: its records and cloud (~33), a voxel grid's
// sums (~44 per voxel), its centroids and their voxel indices (~40); ROR's kd-tree is less.
inline constexpr double kFilterBytesPerPoint = 120.0;
// Bytes per point a tile needs while its LOD tiles or metrics are made (its points with
// attributes, the octree's copies, the metrics' cell grid).
inline constexpr double kOutputBytesPerPoint = 80.0;

struct TiledMapsOptions {
  // Spill buffers of the store (bytes) and the largest working set of a tile being filtered or
  // read (bytes, per thread).
  size_t buffer_budget_bytes = 256u << 20;
  size_t tile_budget_bytes = 128u << 20;
  int threads = 2;
  // The halo of the output tiles (the metrics' radius; 0: none).
  double output_halo_m = 0.25;
  double filter_tile_edge_m = 10.0;
};

// How the map stage shares its memory budget (map.memory_budget_mb): a quarter for the spill
// store's buffers, a quarter for the tiles being filtered or read (shared by the threads), and
// the other half for the output tasks (a map's Draco file, made only when it fits there). What
// the scans hold (a few scans per thread, an intermediary map per sensor, the poses) is
// outside it.
inline constexpr double kSpillShare = 0.25;
inline constexpr double kTileShare = 0.25;
inline constexpr double kOutputShare = 0.5;
TiledMapsOptions tiled_maps_options_for_budget(double budget_bytes, int threads,
                                               double output_halo_m);

// A budget that cannot hold one tile: the message names the tile and the smallest budget that
// would do (`minimum_bytes`).
class TileBudgetError : public std::runtime_error {
 public:
  TileBudgetError(const std::string& message, double minimum_bytes)
      : std::runtime_error(message), minimum_bytes_(minimum_bytes) {}
  double minimum_bytes() const { return minimum_bytes_; }

 private:
  double minimum_bytes_;
};

struct TiledFilterStats {
  size_t tiles = 0;        // filtered (after splits)
  size_t splits = 0;       // tiles split for the budget
  size_t halo_points = 0;  // read besides the tiles' own
  size_t points_in = 0;    // the final stage's input
  size_t largest_tile_points = 0;
  std::vector<mapping::FilterStep> steps;  // summed over tiles: the whole map's counts
};

class TiledMaps {
 public:
  // `sensors`: name and final chain of each map. The spill file goes to `spill_folder`.
  TiledMaps(const std::filesystem::path& spill_folder,
            const std::vector<std::pair<std::string, mapping::FilterChain>>& sensors,
            TiledMapsOptions options);
  ~TiledMaps();

  // The points leaving a sensor's intermediary stage, in feed order (MapBuilder's final sink;
  // calls for one sensor must not overlap).
  void add_final_input(const std::string& sensor, const PointCloud& points);
  // Runs the sensor's final filters tile by tile into the output tiles. Throws
  // TileBudgetError when a tile cannot be made to fit the tile budget.
  void filter_sensor(const std::string& sensor, const std::function<void()>& check_canceled);
  const TiledFilterStats& filter_stats(const std::string& sensor) const;

  // SLAM-map points (the map "slam"), straight into the output tiles; calls must not overlap.
  void add_slam_points(const PointCloud& points);
  void finish_slam();

  // Maps: the sensors' names and "slam". Output points of a map, and whether it has intensity.
  size_t points(const std::string& map) const;
  bool has_intensity(const std::string& map) const;

  // Output tiles that partition the map made of `maps` (sensor names, "slam"), sorted, each
  // small enough to read with its halo within the tile budget: level-0 tiles, or the children
  // of those too dense, made by splitting (copies: the larger tiles stay whole for other
  // readers, so a partition stays valid while another is made). Thread-safe. Throws
  // TileBudgetError for a tile that cannot be split further. Call only once every map in
  // `maps` is complete.
  std::vector<mapping::TileKey> output_partition(const std::vector<std::string>& maps);
  const mapping::TileGrid& output_grid() const { return output_grid_; }
  // Core points of a map in one tile (and with_halo: then its halo, after them; *owned =
  // number of core points).
  PointCloud load(const std::string& map, const mapping::TileKey& tile, bool with_halo = false,
                  size_t* owned = nullptr) const;
  // Points in a tile over all maps in `maps` (cores, and halos when with_halo).
  uint64_t tile_points(const std::vector<std::string>& maps, const mapping::TileKey& tile,
                       bool with_halo) const;
  // Forgets a map's tiles (their memory).
  void erase(const std::string& map);

  const io::SpillStore& store() const { return *store_; }
  const TiledMapsOptions& options() const { return options_; }

 private:
  struct Sensor;
  Sensor& sensor(const std::string& name);
  const Sensor& sensor(const std::string& name) const;
  uint16_t output_cloud(const std::string& map) const;
  void emit(const Sensor& sensor, const PointCloud& owned_points);
  void split_filter_tiles(Sensor& s, std::vector<mapping::TileKey>& keys);
  void partition_into(const std::vector<std::string>& maps, const mapping::TileKey& tile,
                      std::vector<mapping::TileKey>& out);

  TiledMapsOptions options_;
  std::unique_ptr<io::SpillStore> store_;
  mapping::TileGrid output_grid_;
  HaloFunction output_halo_;
  std::vector<std::unique_ptr<Sensor>> sensors_;
  std::unique_ptr<TileBinner> slam_binner_;
  size_t slam_points_ = 0;
  bool slam_intensity_ = true;
  std::mutex split_mutex_;
  std::set<std::pair<uint16_t, mapping::TileKey>> split_;  // (output cloud, tile) split
};

}  // namespace keel::pipeline
