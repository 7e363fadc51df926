#include "worker/compare/local_registration.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <stdexcept>

#include "core/parallel_for.h"
#include "worker/compare/cell_sort.h"
#include "worker/compare/point_grid.h"
#include "worker/compare/voxel_moments.h"

namespace keel::compare {

TileKey tile_of(const Eigen::Vector3f& p, double side) {
  return {int64_t(std::floor(p.x() / side)), int64_t(std::floor(p.y() / side)),
          int64_t(std::floor(p.z() / side))};
}

namespace {

using Key = TileKey;
using Tiles = std::map<Key, std::vector<uint32_t>>;

int bits_for(int64_t largest) {
  int bits = 0;
  while (bits < 63 && (largest >> bits) != 0) ++bits;
  return bits;
}

// Each tile's points in increasing index order. The tiles' keys, packed from the lowest tile
// up, are radix-sorted with the point indices: a map lookup for each of ten million points
// cost ~20 times more.
Tiles bucket(const std::vector<Eigen::Vector3f>& points, double side, int threads) {
  std::vector<Key> keys(points.size());
  keel::parallel_for(points.size(), threads, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) keys[i] = tile_of(points[i], side);
  });
  Tiles tiles;
  if (points.empty()) return tiles;
  Key lo = keys.front(), hi = keys.front();
  for (const Key& k : keys)
    for (int axis = 0; axis < 3; ++axis)
      lo[axis] = std::min(lo[axis], k[axis]), hi[axis] = std::max(hi[axis], k[axis]);
  std::array<int, 3> bits;
  for (int axis = 0; axis < 3; ++axis) bits[axis] = bits_for(hi[axis] - lo[axis]);
  if (bits[0] + bits[1] + bits[2] > 63) {  // tiles too spread to pack: one lookup per point
    for (size_t i = 0; i < points.size(); ++i) tiles[keys[i]].push_back(uint32_t(i));
    return tiles;
  }
  KeyedIndices keyed(points.size(), bits[0] + bits[1] + bits[2]);
  for (size_t i = 0; i < points.size(); ++i)
    keyed.set(i,
              uint64_t(keys[i][0] - lo[0]) << (bits[1] + bits[2]) |
                  uint64_t(keys[i][1] - lo[1]) << bits[2] | uint64_t(keys[i][2] - lo[2]),
              uint32_t(i));
  keyed.sort();
  for (size_t begin = 0; begin < keyed.size();) {
    size_t end = begin;
    while (end < keyed.size() && keyed.key(end) == keyed.key(begin)) ++end;
    std::vector<uint32_t>& members = tiles[keys[keyed.index(begin)]];
    members.reserve(end - begin);
    for (size_t k = begin; k < end; ++k) members.push_back(keyed.index(k));
    begin = end;
  }
  return tiles;
}

// The defined cores grouped by tile, in key order.
std::map<Key, std::vector<CoreSample>> cores_by_tile(const std::vector<CoreChange>& changes,
                                                     double side,
                                                     std::vector<std::vector<size_t>>* members) {
  std::map<Key, std::vector<size_t>> index;
  for (size_t i = 0; i < changes.size(); ++i)
    if (changes[i].defined()) index[tile_of(changes[i].position, side)].push_back(i);
  std::map<Key, std::vector<CoreSample>> out;
  for (const auto& [key, list] : index) {
    std::vector<CoreSample>& samples = out[key];
    samples.reserve(list.size());
    for (size_t i : list) {
      const CoreChange& c = changes[i];
      samples.push_back({c.position.cast<double>(), c.normal.cast<double>(), double(c.distance_m),
                         double(c.statistical_m)});
    }
    if (members) members->push_back(list);
  }
  return out;
}

}  // namespace

LocalRegistration register_tiles(const std::vector<Eigen::Vector3f>& reference,
                                 std::vector<Eigen::Vector3f>* moving,
                                 const LocalRegistrationOptions& o) {
  if (!(o.tile_m > 0) || !(o.core_spacing_m > 0))
    throw std::invalid_argument("local registration: expected tile_m > 0, core_spacing_m > 0");
  validate(o.m3c2);
  const int threads = std::max(1, o.threads);
  LocalRegistration out;
  if (reference.empty() || moving->empty()) return out;

  // 1. The change at B's registration cores, as the measurement takes it (compare_maps.cc).
  const size_t stride = std::max<size_t>(1, o.point_stride);
  std::vector<Eigen::Vector3f> a, b;
  a.reserve(reference.size() / stride + 1);
  b.reserve(moving->size() / stride + 1);
  for (size_t i = 0; i < reference.size(); i += stride) a.push_back(reference[i]);
  for (size_t i = 0; i < moving->size(); i += stride) b.push_back((*moving)[i]);
  std::unique_ptr<PointGrid> grid_a, grid_b;
  VoxelMoments normals_a, normals_b, cores;
  const double cell = 0.5 * o.m3c2.projection_scale_m, normal_voxel = o.m3c2.normal_scale_m / 4.0;
  keel::parallel_for_each(5, threads, [&](size_t k) {
    if (k == 0) grid_a = std::make_unique<PointGrid>(a, cell);
    if (k == 1) grid_b = std::make_unique<PointGrid>(b, cell);
    if (k == 2) cores = voxelize(b, o.core_spacing_m);
    if (k == 3) normals_a = voxelize(a, normal_voxel);
    if (k == 4) normals_b = voxelize(b, normal_voxel);
  });
  M3c2Options mo = o.m3c2;
  mo.registration_error_m = 0.0;
  mo.threads = threads;
  mo.check_canceled = o.check_canceled;
  const std::vector<CoreChange> changes = m3c2(
      {nullptr, nullptr, &normals_a, &normals_b, grid_a.get(), grid_b.get()}, cores.means, {}, mo);
  grid_a.reset();
  grid_b.reset();

  // 2. Each tile's correction from its cores, side by side, largest tiles first.
  const std::map<Key, std::vector<CoreSample>> tiles = cores_by_tile(changes, o.tile_m, nullptr);
  std::vector<const std::pair<const Key, std::vector<CoreSample>>*> list;
  for (const auto& entry : tiles) list.push_back(&entry);
  std::vector<size_t> order(list.size());
  for (size_t t = 0; t < order.size(); ++t) order[t] = t;
  std::stable_sort(order.begin(), order.end(), [&](size_t x, size_t y) {
    return list[x]->second.size() > list[y]->second.size();
  });
  out.tiles.resize(list.size());
  keel::parallel_for_each(order.size(), threads, [&](size_t k) {
    const size_t t = order[k];
    const Key& key = list[t]->first;
    TileRegistration& r = out.tiles[t];
    r.key = key;
    r.center_m =
        (Eigen::Vector3d(key[0], key[1], key[2]) + Eigen::Vector3d::Constant(0.5)) * o.tile_m;
    r.correction = correct_tile(list[t]->second, r.center_m, 0.5 * o.tile_m, o.tile);
  });

  // 3. The corrections applied to B's points.
  std::map<Key, const TileRegistration*> applied;
  for (const TileRegistration& r : out.tiles)
    if (r.correction.applied()) applied[r.key] = &r, ++out.adjusted;
  if (applied.empty()) return out;
  const Tiles points = bucket(*moving, o.tile_m, threads);
  std::vector<std::pair<const std::vector<uint32_t>*, Pose3>> moves;
  for (const auto& [key, members] : points) {
    const auto it = applied.find(key);
    if (it != applied.end()) moves.emplace_back(&members, it->second->correction.T_corrected_b);
  }
  keel::parallel_for_each(moves.size(), threads, [&](size_t m) {
    for (uint32_t i : *moves[m].first)
      (*moving)[i] = (moves[m].second * (*moving)[i].cast<double>()).cast<float>();
  });
  return out;
}

std::vector<double> tile_registration_errors(const std::vector<CoreChange>& changes, double tile_m,
                                             double fallback_m, double confidence_z,
                                             const TileCorrectionOptions& options, int threads,
                                             std::vector<TileError>* figures,
                                             std::vector<char>* stable) {
  if (!(tile_m > 0)) throw std::invalid_argument("registration error: expected tile_m > 0");
  std::vector<std::vector<size_t>> members;
  const std::map<Key, std::vector<CoreSample>> tiles = cores_by_tile(changes, tile_m, &members);
  std::vector<TileError> errors(tiles.size());
  std::vector<std::vector<char>> masks(tiles.size());
  std::vector<const std::pair<const Key, std::vector<CoreSample>>*> list;
  for (const auto& entry : tiles) list.push_back(&entry);
  keel::parallel_for_each(list.size(), threads, [&](size_t t) {
    TileError& e = errors[t];
    e.key = list[t]->first;
    e.cores = list[t]->second.size();
    e.registration_error_m =
        tile_registration_error(list[t]->second, confidence_z, options, &masks[t]);
    e.stable = size_t(std::count(masks[t].begin(), masks[t].end(), 1));
  });
  std::vector<double> out(changes.size(), fallback_m);
  if (stable) stable->assign(changes.size(), 0);
  for (size_t t = 0; t < errors.size(); ++t) {
    for (size_t k = 0; k < members[t].size(); ++k) {
      if (errors[t].registration_error_m >= 0) out[members[t][k]] = errors[t].registration_error_m;
      if (stable) (*stable)[members[t][k]] = masks[t][k];
    }
  }
  if (figures) *figures = std::move(errors);
  return out;
}

}  // namespace keel::compare
