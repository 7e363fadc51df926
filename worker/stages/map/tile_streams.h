// Points in tiles on a SpillStore (issue 17): each tile of a cloud has a core stream (its own
// points) and a halo stream (copies of its neighbours' points within the halo it needs), as
// 16-byte records, appended in feed order. TileBinner sorts points into them; split_tile
// redistributes a tile too dense to process into its 8 children.
#pragma once

#include <cstdint>
#include <functional>
#include <unordered_map>
#include <vector>

#include "core/point_cloud.h"
#include "worker/io/cloud/spill_store.h"
#include "worker/mapping/tile_grid.h"

namespace keel::pipeline {

// x, y, z (world, m) and intensity (NaN when the cloud has none).
struct PointRecord {
  float x, y, z, intensity;
};
static_assert(sizeof(PointRecord) == 16);

enum class TileStream : uint8_t { kCore = 0, kHalo = 1 };

io::StreamKey stream_key(uint16_t cloud, TileStream kind, const mapping::TileKey& tile);
mapping::TileKey tile_of_key(const io::StreamKey& key);

std::vector<PointRecord> read_records(const io::SpillStore& store, const io::StreamKey& key);
// Records as a PointCloud (intensity kept when `with_intensity`).
void append_records(const std::vector<PointRecord>& records, bool with_intensity, PointCloud& out);

// The halo (m) a tile needs around its box; 0 everywhere for none.
using HaloFunction = std::function<double(const mapping::Box&)>;

// Sorts points of one cloud into its tiles' core and halo streams. Not thread-safe; the store
// is. Keeps per-stream batches and appends them to the store on flush() (or when a batch
// fills), so the store's lock is taken per batch, not per point.
class TileBinner {
 public:
  TileBinner(io::SpillStore& store, uint16_t cloud, const mapping::TileGrid& grid,
             HaloFunction halo, bool has_halo, int level = 0);
  ~TileBinner();  // flushes (errors then are lost: call flush() first)
  void add(const PointRecord& record);
  void add(const PointCloud& points);  // intensity NaN when the cloud has none
  void flush();

 private:
  void push(TileStream kind, const mapping::TileKey& tile, const PointRecord& record);
  void bin(const PointRecord& record, bool core);

  io::SpillStore& store_;
  uint16_t cloud_;
  const mapping::TileGrid& grid_;
  HaloFunction halo_;
  bool has_halo_;
  int level_;
  std::unordered_map<io::StreamKey, std::vector<PointRecord>, io::StreamKeyHash> batches_;
  size_t batched_ = 0;
  // The binner runs on the map's serial commit path, so per-point lookups are kept few: each
  // home tile's halo reach is computed once (up to 2^16 neighbour boxes in all, 3.5 MiB, then
  // again), and the core batch of the last point's tile is at hand for the next (consecutive
  // points mostly share it).
  std::unordered_map<mapping::TileKey, mapping::TileGrid::HaloReach, mapping::TileKeyHash> reaches_;
  size_t reach_neighbours_ = 0;  // neighbour boxes held in reaches_
  mapping::TileKey core_tile_;
  std::vector<PointRecord>* core_batch_ = nullptr;  // batches_[core_tile_'s core key]
};

// Makes the core and halo streams of tile `tile`'s children (level + 1) for each cloud in
// `clouds`, keeping feed order; the children's halos come from the tile's own points and from
// its halo. `erase_parent`: the tile's streams go (else they stay whole for readers that use
// them). Returns the children that hold core points of any of the clouds.
std::vector<mapping::TileKey> split_tile(io::SpillStore& store, const std::vector<uint16_t>& clouds,
                                         const mapping::TileGrid& grid,
                                         const mapping::TileKey& tile, const HaloFunction& halo,
                                         bool has_halo, bool erase_parent);

}  // namespace keel::pipeline
