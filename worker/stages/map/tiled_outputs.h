// A map's outputs made from its tiles (issue 17), one tile in memory at a time per thread: the
// metrics of Table V (Eqs. (23)-(26)), the PLY file, and the tiles' budget. A map is one or
// more of TiledMaps' maps (a sensor, "slam", or every sensor for the combined map of Eq. (21)),
// read tile by tile over a partition (TiledMaps::output_partition of the parts), each tile's
// parts in order.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "worker/mapping/map_metrics.h"
#include "worker/stages/map/map_lod.h"
#include "worker/stages/map/tiled_maps.h"

namespace keel::pipeline {

// The metrics of the map made of `parts`: query points strided evenly over it in tile order
// (options.max_query_points; 0: every point), as mapping::compute_map_metrics strides a map in
// memory, each with its neighbours from its tile and the tile's halo, which is as wide as the
// radius (TiledMapsOptions::output_halo_m), so every neighbourhood is the whole map's.
mapping::MapMetrics tiled_map_metrics(const TiledMaps& maps, const std::vector<std::string>& parts,
                                      const std::vector<mapping::TileKey>& tiles,
                                      const mapping::MapMetricsOptions& options);

// Writes the map made of `parts` as a binary PLY (the layout of io::write_ply_cloud: float x, y,
// z, then float intensity when every part has it), tile by tile.
void write_tiled_ply(const TiledMaps& maps, const std::vector<std::string>& parts,
                     const std::vector<mapping::TileKey>& tiles, const std::filesystem::path& path,
                     const std::function<void()>& check_canceled = {});

// The map made of `parts` gathered in memory, in tile order (intensity kept when every part
// has it), for the outputs that need a whole map (a single Draco file).
PointCloud gather_tiled_map(const TiledMaps& maps, const std::vector<std::string>& parts,
                            const std::vector<mapping::TileKey>& tiles);

// The LOD tileset (`tar`, docs/artifacts.md) of the map made of `parts`, named `map`:
// attribute `intensity` when every part has it, and `sensor` (the part's index, its name in
// extras.keel.sensors) when there are several parts.
MapTilesetResult write_tiled_tileset(const TiledMaps& maps, const std::vector<std::string>& parts,
                                     const std::vector<mapping::TileKey>& tiles,
                                     const std::string& map, const std::filesystem::path& tar,
                                     const mapping::LodOptions& options,
                                     const std::function<void()>& check_canceled = {});

}  // namespace keel::pipeline
