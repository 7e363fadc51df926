// A map's level-of-detail tileset (issue 17, docs/artifacts.md "Level-of-detail tiles") from its
// tiles on a TileGrid: the grid's tiles are the cubes at one depth of an octree whose root
// covers them all; each tile is loaded once, its own subtree built (mapping::build_lod_subtree)
// and its thinned points kept until its parent's are made, so memory holds one tile and the
// coarser levels, never the map. Tiles split for the memory budget (TileKey levels > 0) are
// deeper cubes of the same octree.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "worker/io/cloud/tileset_writer.h"
#include "worker/mapping/lod_octree.h"
#include "worker/mapping/tile_grid.h"

namespace keel::pipeline {

struct LodTileSource {
  // The tiles holding the map's points: level-0 keys, or the children of split ones.
  std::vector<mapping::TileKey> tiles;
  // The map's points in one tile, attributes in the tileset's order.
  std::function<mapping::LodPoints(const mapping::TileKey&)> load;
};

struct MapTilesetResult {
  nlohmann::json tileset;  // tileset.json as written
  size_t tiles = 0;
  uint64_t points = 0, bytes = 0;
  double seconds = 0.0;
};

// Writes `tar` (tiles_<map>.tar). Throws std::invalid_argument for a source without tiles.
MapTilesetResult write_map_tileset(const std::filesystem::path& tar, const mapping::TileGrid& grid,
                                   const LodTileSource& source,
                                   const std::vector<io::PntsAttribute>& attributes,
                                   nlohmann::json extras, const mapping::LodOptions& options,
                                   const std::function<void()>& check_canceled = {});

}  // namespace keel::pipeline
