#include "worker/mapping/tiled_filter.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "worker/mapping/cloud_ops.h"
#include "worker/mapping/voxel_accumulator.h"

namespace keel::mapping {
namespace {

template <class... Ts>
struct Overloaded : Ts... {
  using Ts::operator()...;
};
template <class... Ts>
Overloaded(Ts...) -> Overloaded<Ts...>;

// DROR's largest search radius over a box: at its farthest horizontal corner from the origin.
double dror_max_radius(const DrorFilter& filter, const Box& box) {
  const double x = std::max(std::abs(box.min.x()), std::abs(box.max.x()));
  const double y = std::max(std::abs(box.min.y()), std::abs(box.max.y()));
  return dror_search_radius(filter, std::sqrt(x * x + y * y));
}

size_t count_owned(const std::vector<uint8_t>& owned) {
  return static_cast<size_t>(
      std::count_if(owned.begin(), owned.end(), [](uint8_t o) { return o; }));
}

void keep_with_flags(TileWork& work, const std::vector<uint8_t>& keep) {
  size_t out = 0;
  for (size_t k = 0; k < keep.size(); ++k)
    if (keep[k]) work.owned[out++] = work.owned[k];
  work.owned.resize(out);
  keep_points(work.points, keep);
}

// The voxel grid over the whole working set; a centroid is owned when its voxel is the tile's.
void voxelize(const VoxelGridFilter& filter, const TileGrid& grid, const TileKey& tile,
              TileWork& work) {
  VoxelAccumulator voxels(filter.leaf_m);
  voxels.add(work.points);
  PointCloud centroids = voxels.centroids();
  const std::vector<VoxelKey> keys = voxels.voxels();
  work.owned.assign(keys.size(), 0);
  for (size_t k = 0; k < keys.size(); ++k)
    work.owned[k] = grid.tile_of_voxel(keys[k], filter.leaf_m, tile.level) == tile;
  centroids.t_ns = work.points.t_ns;
  centroids.frame = work.points.frame;
  work.points = std::move(centroids);
}

}  // namespace

double tile_unit_for(const FilterChain& chain, double fallback_m) {
  for (const FilterSpec& filter : chain.filters)
    if (const auto* voxel = std::get_if<VoxelGridFilter>(&filter)) return voxel->leaf_m;
  return fallback_m;
}

double chain_halo_m(const FilterChain& chain, const TileGrid& grid, const Box& tile_box) {
  double halo = 0.0;  // 0: exactly the tile's own points are needed
  for (auto it = chain.filters.rbegin(); it != chain.filters.rend(); ++it) {
    std::visit(Overloaded{[](const CropBoxFilter&) {},  // decides each point by itself
                          [&](const VoxelGridFilter& f) {
                            // The tile's own voxels hold only its own points (the grid's unit).
                            if (halo == 0.0 && f.leaf_m == grid.unit_m()) return;
                            halo += f.leaf_m + kHaloMarginM;  // whole voxels around what is needed
                          },
                          [&](const RadiusOutlierFilter& f) { halo += f.radius_m + kHaloMarginM; },
                          [&](const DrorFilter& f) {
                            halo += dror_max_radius(f, tile_box.expanded(halo)) + kHaloMarginM;
                          }},
               *it);
  }
  return halo;
}

std::vector<FilterStep> filter_tile(const FilterChain& chain, const TileGrid& grid,
                                    const TileKey& tile, TileWork& work, int threads) {
  if (work.owned.size() != work.points.size())
    throw std::invalid_argument("filter_tile: " + std::to_string(work.owned.size()) +
                                " ownership flags for " + std::to_string(work.points.size()) +
                                " points");
  check_field_sizes(work.points, "filter_tile points");
  std::vector<FilterStep> steps;
  for (const FilterSpec& filter : chain.filters) {
    const size_t owned_in = count_owned(work.owned);
    std::visit(Overloaded{[&](const CropBoxFilter& f) {
                            keep_with_flags(work, crop_box_keep(f, work.points.xyz));
                          },
                          [&](const VoxelGridFilter& f) { voxelize(f, grid, tile, work); },
                          [&](const RadiusOutlierFilter& f) {
                            keep_with_flags(work, radius_outlier_keep(f, work.points.xyz, threads));
                          },
                          [&](const DrorFilter& f) {
                            keep_with_flags(work, dror_keep(f, work.points.xyz, threads));
                          }},
               filter);
    steps.push_back(FilterStep{filter_type(filter), owned_in, count_owned(work.owned)});
  }
  keep_points(work.points, work.owned);
  work.owned.assign(work.points.size(), 1);
  return steps;
}

}  // namespace keel::mapping
