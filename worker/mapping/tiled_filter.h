// A filter chain run tile by tile (issue 17): each tile is filtered together with a halo of its
// neighbours' points as wide as the chain's neighbourhoods, and keeps the points it owns, so
// the union over tiles is the chain over the whole map, point for point.
//
// Ownership: a tile owns its own input points (its "core"; halo points are owned by their
// tiles), a voxel grid's centroid belongs to the tile of its voxel (TileGrid::tile_of_voxel, a
// pure function of the voxel index), and crop boxes, ROR and DROR keep points as they are. So
// every output point of the whole-map chain is owned by exactly one tile. Each tile computes its
// owned points exactly when the halo holds every point they depend on (chain_halo_m), and when
// each voxel's points are summed in the same order as over the whole map: with the grid unit
// equal to a chain's only voxel leaf, a voxel's points all come from one tile, in feed order, so
// the centroids are bit for bit the same. (A second voxel grid of another leaf sums centroids
// in a tile's order: equal up to float rounding.)
#pragma once

#include <cstdint>
#include <vector>

#include "core/point_cloud.h"
#include "worker/mapping/filter_chain.h"
#include "worker/mapping/tile_grid.h"

namespace keel::mapping {

// The grid unit that keeps a chain's voxels whole in tiles: its first voxel grid's leaf, else
// `fallback_m`.
double tile_unit_for(const FilterChain& chain, double fallback_m);

// The halo (metres, around the box of a tile) that the tile needs for `chain`, walking the chain
// backwards from "the tile's owned output": a crop box needs nothing more; ROR and DROR need
// every point within their radius (DROR's largest radius over the grown box); a voxel grid
// needs whole voxels around what is needed after it (nothing around a tile when only the
// tile's own voxels are needed and the leaf is the grid unit). Each step adds a margin of
// kHaloMarginM for rounding.
double chain_halo_m(const FilterChain& chain, const TileGrid& grid, const Box& tile_box);
inline constexpr double kHaloMarginM = 1e-3;

// The points of one tile: its core and then its halo, each in feed order; owned[k] != 0 for
// core points.
struct TileWork {
  PointCloud points;
  std::vector<uint8_t> owned;
};

// Runs `chain` on `work` (tile `tile` of `grid`) and leaves in it the tile's owned output
// points only, in order. Per filter, the points in and out it counts are the owned ones, so the
// sums over all tiles are the whole-map chain's counts.
std::vector<FilterStep> filter_tile(const FilterChain& chain, const TileGrid& grid,
                                    const TileKey& tile, TileWork& work, int threads = 1);

}  // namespace keel::mapping
