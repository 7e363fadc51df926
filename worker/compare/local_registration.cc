#include "worker/compare/local_registration.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <optional>
#include <stdexcept>

#include "worker/compare/cell_sort.h"
#include "core/parallel_for.h"

namespace keel::compare {
namespace {

using Key = std::array<int64_t, 3>;
using Tiles = std::map<Key, std::vector<uint32_t>>;

Key tile_of(const Eigen::Vector3f& p, double side) {
  return {int64_t(std::floor(p.x() / side)), int64_t(std::floor(p.y() / side)),
          int64_t(std::floor(p.z() / side))};
}

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

struct TileShift {
  Pose3 T_a_b = Pose3::Identity();
  double shift_m = 0.0;  // the translation at the tile's centre
};

// The tile's own transform when it is well determined and small, else nothing.
std::optional<TileShift> register_tile(const std::vector<Eigen::Vector3f>& reference,
                                       const Tiles& tiles_a, const Key& key,
                                       const std::vector<Eigen::Vector3f>& b,
                                       const LocalRegistrationOptions& o) {
  const Eigen::Vector3d lo = Eigen::Vector3d(key[0], key[1], key[2]) * o.tile_m;
  const Eigen::Vector3d hi = lo + Eigen::Vector3d::Constant(o.tile_m);
  std::vector<Eigen::Vector3f> a;
  for (int64_t dx = -1; dx <= 1; ++dx)
    for (int64_t dy = -1; dy <= 1; ++dy)
      for (int64_t dz = -1; dz <= 1; ++dz) {
        const auto it = tiles_a.find({key[0] + dx, key[1] + dy, key[2] + dz});
        if (it == tiles_a.end()) continue;
        for (uint32_t i : it->second) {
          const Eigen::Vector3d p = reference[i].cast<double>();
          if ((p.array() >= lo.array() - o.margin_m).all() &&
              (p.array() <= hi.array() + o.margin_m).all())
            a.push_back(reference[i]);
        }
      }
  if (a.size() < o.min_points) return std::nullopt;
  StableRegistrationOptions ro = o.registration;
  ro.threads = 1;  // the tiles run side by side
  StableRegistration r;
  try {
    r = register_stable(a, b, Pose3::Identity(), ro);
  } catch (const std::runtime_error&) {
    return std::nullopt;  // no surfaces or too few stable pairs: the global transform stands
  }
  const Eigen::Vector3d center = 0.5 * (lo + hi);
  const double shift = (r.T_a_b * center - center).norm();
  const double angle_deg = Eigen::AngleAxisd(r.T_a_b.linear()).angle() * 180.0 / M_PI;
  if (!r.converged || r.stable < o.min_stable_pairs || r.conditioning < o.min_conditioning ||
      shift > o.max_translation_m || angle_deg > o.max_rotation_deg)
    return std::nullopt;
  return TileShift{r.T_a_b, shift};
}

}  // namespace

LocalRegistration register_tiles(const std::vector<Eigen::Vector3f>& reference,
                                 std::vector<Eigen::Vector3f>* moving,
                                 const LocalRegistrationOptions& o) {
  if (!(o.tile_m > 0) || !(o.margin_m >= 0) || o.margin_m > o.tile_m)
    throw std::invalid_argument("local registration: expected tile_m > 0, 0 <= margin_m <= tile_m");
  const int threads = std::max(1, o.registration.threads);
  const Tiles tiles_b = bucket(*moving, o.tile_m, threads);
  const Tiles tiles_a = bucket(reference, o.tile_m, threads);
  std::vector<Tiles::const_iterator> registered;  // B's tiles with enough points, in key order
  for (auto it = tiles_b.begin(); it != tiles_b.end(); ++it)
    if (it->second.size() >= o.min_points) registered.push_back(it);

  // Each tile reads only its own points of B: the tiles register side by side, and move their
  // points once all are done.
  // Largest tiles first, so that no large one starts last while the other threads idle.
  std::vector<size_t> order(registered.size());
  for (size_t t = 0; t < order.size(); ++t) order[t] = t;
  std::stable_sort(order.begin(), order.end(), [&](size_t x, size_t y) {
    return registered[x]->second.size() > registered[y]->second.size();
  });
  std::vector<std::optional<TileShift>> shifts(registered.size());
  keel::parallel_for_each(order.size(), threads, [&](size_t k) {
    const size_t t = order[k];
    std::vector<Eigen::Vector3f> b;
    b.reserve(registered[t]->second.size());
    for (uint32_t i : registered[t]->second) b.push_back((*moving)[i]);
    shifts[t] = register_tile(reference, tiles_a, registered[t]->first, b, o);
  });

  LocalRegistration out;
  out.tiles = registered.size();
  for (size_t t = 0; t < registered.size(); ++t) {
    if (!shifts[t]) continue;
    for (uint32_t i : registered[t]->second)
      (*moving)[i] = (shifts[t]->T_a_b * (*moving)[i].cast<double>()).cast<float>();
    ++out.adjusted;
    out.correction_m.push_back(shifts[t]->shift_m);
  }
  return out;
}

}  // namespace keel::compare
