#include "worker/mapping/tile_grid.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <tuple>

namespace keel::mapping {
namespace {

// floor(a / b) for b > 0.
int64_t floor_div(int64_t a, int64_t b) {
  const int64_t q = a / b;
  return (a % b != 0 && a < 0) ? q - 1 : q;
}

int32_t to_tile_coordinate(int64_t value) {
  if (value < INT32_MIN || value > INT32_MAX)
    throw std::invalid_argument("tile grid: tile index " + std::to_string(value) +
                                " does not fit 32 bits");
  return static_cast<int32_t>(value);
}

// The largest radius searched for halo neighbours, in tiles (a halo wider than this many tiles
// means tiles far too small for the filters).
constexpr int kMaxReachTiles = 16;

}  // namespace

bool TileKey::operator<(const TileKey& o) const {
  return std::tie(level, z, y, x) < std::tie(o.level, o.z, o.y, o.x);
}

std::string TileKey::to_string() const {
  return "(" + std::to_string(x) + ", " + std::to_string(y) + ", " + std::to_string(z) +
         ") level " + std::to_string(level);
}

size_t TileKeyHash::operator()(const TileKey& key) const {
  return static_cast<size_t>(voxel_hash(VoxelKey{key.x, key.y, key.z}) ^
                             (uint64_t{key.level} * 0x9e3779b97f4a7c15ULL));
}

Box Box::expanded(double margin) const {
  return Box{min - Eigen::Vector3d::Constant(margin), max + Eigen::Vector3d::Constant(margin)};
}

bool Box::contains(const Eigen::Vector3d& p) const {
  return (p.array() >= min.array()).all() && (p.array() <= max.array()).all();
}

TileGrid::TileGrid(double unit_m, int64_t units_per_tile)
    : unit_m_(unit_m), inverse_unit_(1.0 / unit_m), units_per_tile_(units_per_tile) {
  if (!std::isfinite(unit_m) || unit_m <= 0.0)
    throw std::invalid_argument("tile grid: unit must be a positive number of metres, got " +
                                std::to_string(unit_m));
  if (units_per_tile < 1 || units_per_tile > (int64_t{1} << 20) ||
      (units_per_tile & (units_per_tile - 1)) != 0)
    throw std::invalid_argument(
        "tile grid: units per tile must be a power of two in [1, 2^20], "
        "got " +
        std::to_string(units_per_tile));
  while ((int64_t{1} << max_level_) < units_per_tile_) ++max_level_;
}

TileGrid TileGrid::with_edge_near(double unit_m, double target_edge_m) {
  const double units = std::max(1.0, target_edge_m / unit_m);
  const int exponent = std::clamp(static_cast<int>(std::lround(std::log2(units))), 0, 20);
  return TileGrid(unit_m, int64_t{1} << exponent);
}

double TileGrid::edge_m(int level) const {
  return unit_m_ * static_cast<double>(units_per_tile_ >> level);
}

TileKey TileGrid::tile_of(const Eigen::Vector3f& p, int level) const {
  const VoxelKey v = voxel_of(p, inverse_unit_);
  const int64_t units = units_per_tile_ >> level;
  return TileKey{to_tile_coordinate(floor_div(v.i, units)),
                 to_tile_coordinate(floor_div(v.j, units)),
                 to_tile_coordinate(floor_div(v.k, units)), static_cast<uint8_t>(level)};
}

TileKey TileGrid::tile_of_voxel(const VoxelKey& voxel, double leaf_m, int level) const {
  const int64_t units = units_per_tile_ >> level;
  if (leaf_m == unit_m_)
    return TileKey{to_tile_coordinate(floor_div(voxel.i, units)),
                   to_tile_coordinate(floor_div(voxel.j, units)),
                   to_tile_coordinate(floor_div(voxel.k, units)), static_cast<uint8_t>(level)};
  const auto axis = [&](int64_t index) {
    const double unit_index = std::floor(static_cast<double>(index) * leaf_m * inverse_unit_);
    return to_tile_coordinate(floor_div(static_cast<int64_t>(unit_index), units));
  };
  return TileKey{axis(voxel.i), axis(voxel.j), axis(voxel.k), static_cast<uint8_t>(level)};
}

Box TileGrid::box(const TileKey& tile) const {
  const double edge = edge_m(tile.level);
  const Eigen::Vector3d min(tile.x * edge, tile.y * edge, tile.z * edge);
  return Box{min, min + Eigen::Vector3d::Constant(edge)};
}

TileKey TileGrid::child(const TileKey& tile, int index) const {
  if (tile.level >= max_level_)
    throw std::invalid_argument("tile grid: tile " + tile.to_string() +
                                " has one unit, no children");
  return TileKey{2 * tile.x + (index & 1), 2 * tile.y + ((index >> 1) & 1),
                 2 * tile.z + ((index >> 2) & 1), static_cast<uint8_t>(tile.level + 1)};
}

TileGrid::HaloReach TileGrid::halo_reach(const TileKey& home,
                                         const std::function<double(const Box&)>& halo_m) const {
  HaloReach out;
  out.home = home;
  out.home_box = box(home);
  const double edge = edge_m(home.level);
  // The halos of the tiles within `reach` tiles are at most that of the home box grown by
  // reach tiles (halos grow with the distance from the origin only): widen until it covers.
  int reach = 1;
  out.widest_m = halo_m(out.home_box.expanded(edge));
  while (out.widest_m > reach * edge) {
    reach = static_cast<int>(std::ceil(out.widest_m / edge));
    if (reach > kMaxReachTiles)
      throw std::invalid_argument("tile grid: the filters' halo (" + std::to_string(out.widest_m) +
                                  " m) spans more than " + std::to_string(kMaxReachTiles) +
                                  " tiles of " + std::to_string(edge) + " m");
    out.widest_m = halo_m(out.home_box.expanded(reach * edge));
  }
  for (int dz = -reach; dz <= reach; ++dz)
    for (int dy = -reach; dy <= reach; ++dy)
      for (int dx = -reach; dx <= reach; ++dx) {
        if (dx == 0 && dy == 0 && dz == 0) continue;
        const TileKey other{home.x + dx, home.y + dy, home.z + dz, home.level};
        const Box other_box = box(other);
        out.neighbours.emplace_back(other, other_box.expanded(halo_m(other_box)));
      }
  return out;
}

void TileGrid::for_each_halo_tile(const Eigen::Vector3f& p, const HaloReach& reach,
                                  const std::function<void(const TileKey&)>& visit) const {
  const Eigen::Vector3d q = p.cast<double>();
  // Most points lie deeper inside their tile than any halo reaches.
  const Box& home = reach.home_box;
  if (((q - home.min).array() > reach.widest_m).all() &&
      ((home.max - q).array() > reach.widest_m).all())
    return;
  for (const auto& [tile, grown] : reach.neighbours)
    if (grown.contains(q)) visit(tile);
}

void TileGrid::for_each_halo_tile(const Eigen::Vector3f& p, const TileKey& home,
                                  const std::function<double(const Box&)>& halo_m,
                                  const std::function<void(const TileKey&)>& visit) const {
  for_each_halo_tile(p, halo_reach(home, halo_m), visit);
}

}  // namespace keel::mapping
