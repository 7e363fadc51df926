#include "worker/compare/local_registration.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <stdexcept>

namespace keel::compare {
namespace {

using Key = std::array<int64_t, 3>;

Key tile_of(const Eigen::Vector3f& p, double side) {
  return {int64_t(std::floor(p.x() / side)), int64_t(std::floor(p.y() / side)),
          int64_t(std::floor(p.z() / side))};
}

}  // namespace

LocalRegistration register_tiles(const std::vector<Eigen::Vector3f>& reference,
                                 std::vector<Eigen::Vector3f>* moving,
                                 const LocalRegistrationOptions& o) {
  if (!(o.tile_m > 0) || !(o.margin_m >= 0) || o.margin_m > o.tile_m)
    throw std::invalid_argument("local registration: expected tile_m > 0, 0 <= margin_m <= tile_m");
  std::map<Key, std::vector<uint32_t>> tiles_b, tiles_a;
  for (size_t i = 0; i < moving->size(); ++i)
    tiles_b[tile_of((*moving)[i], o.tile_m)].push_back(uint32_t(i));
  for (size_t i = 0; i < reference.size(); ++i)
    tiles_a[tile_of(reference[i], o.tile_m)].push_back(uint32_t(i));

  LocalRegistration out;
  for (const auto& [key, members] : tiles_b) {
    if (members.size() < o.min_points) continue;
    ++out.tiles;
    const Eigen::Vector3d lo = Eigen::Vector3d(key[0], key[1], key[2]) * o.tile_m;
    const Eigen::Vector3d hi = lo + Eigen::Vector3d::Constant(o.tile_m);
    std::vector<Eigen::Vector3f> a, b;
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
    for (uint32_t i : members) b.push_back((*moving)[i]);
    if (a.size() < o.min_points) continue;
    StableRegistration r;
    try {
      r = register_stable(a, b, Pose3::Identity(), o.registration);
    } catch (const std::runtime_error&) {
      continue;  // no surfaces or too few stable pairs: the global transform stands
    }
    const Eigen::Vector3d center = 0.5 * (lo + hi);
    const double shift = (r.T_a_b * center - center).norm();
    const double angle_deg = Eigen::AngleAxisd(r.T_a_b.linear()).angle() * 180.0 / M_PI;
    if (!r.converged || r.stable < o.min_stable_pairs || r.conditioning < o.min_conditioning ||
        shift > o.max_translation_m || angle_deg > o.max_rotation_deg)
      continue;
    for (uint32_t i : members) (*moving)[i] = (r.T_a_b * (*moving)[i].cast<double>()).cast<float>();
    ++out.adjusted;
    out.correction_m.push_back(shift);
  }
  return out;
}

}  // namespace keel::compare
