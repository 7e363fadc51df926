#include "tests/sim/analytic_scene.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "tests/sim/rng.h"

namespace keel::sim {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

double hash01(int64_t x, int64_t y, int64_t z) {
  uint64_t h = splitmix64(static_cast<uint64_t>(x) * 0x9E3779B97F4A7C15ULL ^
                          splitmix64(static_cast<uint64_t>(y) + 0x632BE59BD9B4E019ULL) ^
                          splitmix64(static_cast<uint64_t>(z) * 0x85157AF5ULL + 11));
  return static_cast<double>(h >> 11) * 0x1.0p-53;
}

// Slab test of a ray against an axis-aligned box [lo, hi] (local coordinates). Returns the
// entering t and the axis/sign of the entering face.
bool slab(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& lo,
          const Eigen::Vector3d& hi, double t_min, double t_max, double* t_hit, int* axis,
          double* sign) {
  double t_near = -kInf, t_far = kInf;
  int near_axis = -1;
  double near_sign = 0.0;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(d[i]) < 1e-15) {
      if (o[i] < lo[i] || o[i] > hi[i]) return false;
      continue;
    }
    const double inv = 1.0 / d[i];
    double t0 = (lo[i] - o[i]) * inv, t1 = (hi[i] - o[i]) * inv;
    double s = -1.0;  // entering through the low face: normal -axis
    if (t0 > t1) std::swap(t0, t1), s = 1.0;
    if (t0 > t_near) t_near = t0, near_axis = i, near_sign = s;
    t_far = std::min(t_far, t1);
    if (t_near > t_far) return false;
  }
  if (near_axis < 0 || t_near < t_min || t_near > t_max) return false;
  *t_hit = t_near, *axis = near_axis, *sign = near_sign;
  return true;
}

double box_sdf(const Eigen::Vector3d& p_local, const Eigen::Vector3d& lo,
               const Eigen::Vector3d& hi) {
  const Eigen::Vector3d center = 0.5 * (lo + hi), half = 0.5 * (hi - lo);
  const Eigen::Vector3d q = (p_local - center).cwiseAbs() - half;
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}

Eigen::AlignedBox3d world_bounds(const Eigen::Vector3d& center, const Eigen::Matrix3d& R,
                                 const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  Eigen::AlignedBox3d box;
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d c((corner & 1) ? hi.x() : lo.x(), (corner & 2) ? hi.y() : lo.y(),
                            (corner & 4) ? hi.z() : lo.z());
    box.extend(center + R * c);
  }
  return box;
}

class Plane : public Primitive {
 public:
  Plane(const Eigen::Vector3d& point, const Eigen::Vector3d& normal)
      : point_(point), normal_(normal.normalized()) {}
  bool intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min, double t_max,
                 double* t, Eigen::Vector3d* n) const override {
    const double denom = normal_.dot(d);
    if (std::abs(denom) < 1e-12) return false;
    const double th = normal_.dot(point_ - o) / denom;
    if (th < t_min || th > t_max) return false;
    *t = th;
    *n = denom < 0.0 ? normal_ : Eigen::Vector3d(-normal_);
    return true;
  }
  double signed_distance(const Eigen::Vector3d& p) const override {
    return normal_.dot(p - point_);
  }

 private:
  Eigen::Vector3d point_, normal_;
};

class Box : public Primitive {
 public:
  Box(const Eigen::Vector3d& center, const Eigen::Matrix3d& R, const Eigen::Vector3d& half)
      : center_(center), R_(R), half_(half) {
    bounds = world_bounds(center, R, -half, half);
  }
  bool intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min, double t_max,
                 double* t, Eigen::Vector3d* n) const override {
    const Eigen::Vector3d ol = R_.transpose() * (o - center_), dl = R_.transpose() * d;
    int axis;
    double sign;
    if (!slab(ol, dl, -half_, half_, t_min, t_max, t, &axis, &sign)) return false;
    *n = sign * R_.col(axis);
    return true;
  }
  double signed_distance(const Eigen::Vector3d& p) const override {
    return box_sdf(R_.transpose() * (p - center_), -half_, half_);
  }

 private:
  Eigen::Vector3d center_;
  Eigen::Matrix3d R_;
  Eigen::Vector3d half_;
};

// Where a ray inside [lo, hi] leaves it: the exit t and the outward normal of the exit face.
bool slab_exit(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& lo,
               const Eigen::Vector3d& hi, double* t_exit, Eigen::Vector3d* outward) {
  double t_far = kInf;
  int far_axis = -1;
  double far_sign = 0.0;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(d[i]) < 1e-15) continue;
    const double t = ((d[i] > 0.0 ? hi[i] : lo[i]) - o[i]) / d[i];
    if (t < t_far) t_far = t, far_axis = i, far_sign = d[i] > 0.0 ? 1.0 : -1.0;
  }
  if (far_axis < 0) return false;
  *t_exit = t_far;
  *outward = Eigen::Vector3d::Zero();
  (*outward)[far_axis] = far_sign;
  return true;
}

class CavityBox : public Primitive {
 public:
  CavityBox(const Eigen::Vector3d& center, const Eigen::Matrix3d& R, const Eigen::Vector3d& half,
            std::vector<Eigen::AlignedBox3d> cavities)
      : center_(center), R_(R), half_(half), cavities_(std::move(cavities)) {
    bounds = world_bounds(center, R, -half, half);
  }
  bool intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min, double t_max,
                 double* t, Eigen::Vector3d* n) const override {
    const Eigen::Vector3d ol = R_.transpose() * (o - center_), dl = R_.transpose() * d;
    int axis;
    double sign, th;
    if (!slab(ol, dl, -half_, half_, t_min, kInf, &th, &axis, &sign)) return false;
    const Eigen::Vector3d p = ol + th * dl;
    for (const auto& cavity : cavities_) {
      if (!cavity.contains(p)) continue;
      // Inside the mouth: the ray runs on through the cavity to its floor or a wall.
      double t_exit;
      Eigen::Vector3d outward;
      if (!slab_exit(ol, dl, cavity.min(), cavity.max(), &t_exit, &outward)) return false;
      if (t_exit > t_max) return false;
      *t = t_exit;
      *n = -(R_ * outward);
      return true;
    }
    if (th > t_max) return false;
    *t = th;
    Eigen::Vector3d local = Eigen::Vector3d::Zero();
    local[axis] = sign;
    *n = R_ * local;
    return true;
  }
  double signed_distance(const Eigen::Vector3d& p) const override {
    const Eigen::Vector3d pl = R_.transpose() * (p - center_);
    double d = box_sdf(pl, -half_, half_);
    for (const auto& cavity : cavities_) d = std::max(d, -box_sdf(pl, cavity.min(), cavity.max()));
    return d;
  }

 private:
  Eigen::Vector3d center_;
  Eigen::Matrix3d R_;
  Eigen::Vector3d half_;
  std::vector<Eigen::AlignedBox3d> cavities_;
};

class Cylinder : public Primitive {
 public:
  Cylinder(const Eigen::Vector3d& center, const Eigen::Matrix3d& R, double radius,
           double half_height)
      : center_(center), R_(R), radius_(radius), half_height_(half_height) {
    bounds = world_bounds(center, R, Eigen::Vector3d(-radius, -radius, -half_height),
                          Eigen::Vector3d(radius, radius, half_height));
  }
  bool intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min, double t_max,
                 double* t, Eigen::Vector3d* n) const override {
    const Eigen::Vector3d ol = R_.transpose() * (o - center_), dl = R_.transpose() * d;
    double best = kInf;
    Eigen::Vector3d best_normal = Eigen::Vector3d::Zero();
    // Side: (ox + t dx)^2 + (oy + t dy)^2 = r^2, entering root.
    const double a = dl.x() * dl.x() + dl.y() * dl.y();
    if (a > 1e-15) {
      const double b = ol.x() * dl.x() + ol.y() * dl.y();
      const double c = ol.x() * ol.x() + ol.y() * ol.y() - radius_ * radius_;
      const double disc = b * b - a * c;
      if (disc >= 0.0) {
        const double th = (-b - std::sqrt(disc)) / a;
        const double z = ol.z() + th * dl.z();
        if (th >= t_min && th <= t_max && std::abs(z) <= half_height_) {
          best = th;
          best_normal = Eigen::Vector3d(ol.x() + th * dl.x(), ol.y() + th * dl.y(), 0.0) / radius_;
        }
      }
    }
    // Caps.
    if (std::abs(dl.z()) > 1e-15) {
      for (double cap : {-half_height_, half_height_}) {
        const double th = (cap - ol.z()) / dl.z();
        if (th < t_min || th > t_max || th >= best) continue;
        const double x = ol.x() + th * dl.x(), y = ol.y() + th * dl.y();
        if (x * x + y * y > radius_ * radius_) continue;
        if ((cap > 0.0) != (dl.z() < 0.0)) continue;  // must enter through the cap
        best = th;
        best_normal = Eigen::Vector3d(0.0, 0.0, cap > 0.0 ? 1.0 : -1.0);
      }
    }
    if (best == kInf) return false;
    *t = best;
    *n = R_ * best_normal;
    return true;
  }
  double signed_distance(const Eigen::Vector3d& p) const override {
    const Eigen::Vector3d pl = R_.transpose() * (p - center_);
    const Eigen::Vector2d q(std::hypot(pl.x(), pl.y()) - radius_, std::abs(pl.z()) - half_height_);
    return std::min(std::max(q.x(), q.y()), 0.0) + q.cwiseMax(0.0).norm();
  }

 private:
  Eigen::Vector3d center_;
  Eigen::Matrix3d R_;
  double radius_, half_height_;
};

class ReliefWall : public Primitive {
 public:
  explicit ReliefWall(const ReliefWallGeometry& g) : g_(g) {
    R_ = Eigen::AngleAxisd(g.yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    x0_ = -0.5 * g.length_m;
    x1_ = 0.5 * g.length_m;
    bounds = world_bounds(g.center, R_, Eigen::Vector3d(x0_, -g.thickness_m, g.z_min),
                          Eigen::Vector3d(x1_, g.relief_m, g.z_max));
  }

  bool intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min, double t_max,
                 double* t, Eigen::Vector3d* n) const override {
    const Eigen::Vector3d ol = R_.transpose() * (o - g_.center), dl = R_.transpose() * d;
    double best = kInf;
    Eigen::Vector3d best_local_normal = Eigen::Vector3d::Zero();
    int axis;
    double sign, th;
    // Wall body (the mortar plane y = 0 and its sides).
    if (slab(ol, dl, {x0_, -g_.thickness_m, g_.z_min}, {x1_, 0.0, g_.z_max}, t_min, t_max, &th,
             &axis, &sign)) {
      best = th;
      best_local_normal = Eigen::Vector3d::Zero();
      best_local_normal[axis] = sign;
    }
    // Relief slab y in [0, relief]: walk the block cells the ray crosses.
    double ta, tb;
    if (slab_interval(ol, dl, std::max(t_min, 0.0), std::min(t_max, best), &ta, &tb)) {
      double tc = ta;
      for (int guard = 0; guard < 4096 && tc <= tb; ++guard) {
        const Eigen::Vector3d p = ol + tc * dl;
        Eigen::Vector3d lo, hi, cell_lo, cell_hi;
        block_at(p.x(), p.z(), 0, 0, &lo, &hi, &cell_lo, &cell_hi);
        // Exit of the current cell rectangle in x and z.
        double t_exit = tb;
        if (dl.x() > 1e-15) t_exit = std::min(t_exit, (cell_hi.x() - ol.x()) / dl.x());
        if (dl.x() < -1e-15) t_exit = std::min(t_exit, (cell_lo.x() - ol.x()) / dl.x());
        if (dl.z() > 1e-15) t_exit = std::min(t_exit, (cell_hi.z() - ol.z()) / dl.z());
        if (dl.z() < -1e-15) t_exit = std::min(t_exit, (cell_lo.z() - ol.z()) / dl.z());
        if (hi.x() > lo.x() && hi.z() > lo.z() &&
            slab(ol, dl, lo, hi, tc - 1e-9, t_exit + 1e-9, &th, &axis, &sign) && th < best) {
          best = th;
          best_local_normal = Eigen::Vector3d::Zero();
          best_local_normal[axis] = sign;
          break;
        }
        tc = std::max(t_exit, tc) + 1e-7;
      }
    }
    if (best == kInf) return false;
    *t = best;
    *n = R_ * best_local_normal;
    return true;
  }

  double signed_distance(const Eigen::Vector3d& p) const override {
    const Eigen::Vector3d pl = R_.transpose() * (p - g_.center);
    double d = box_sdf(pl, {x0_, -g_.thickness_m, g_.z_min}, {x1_, 0.0, g_.z_max});
    for (int dr = -1; dr <= 1; ++dr) {
      for (int dk = -1; dk <= 1; ++dk) {
        Eigen::Vector3d lo, hi, cl, ch;
        block_at(pl.x(), pl.z(), dr, dk, &lo, &hi, &cl, &ch);
        if (hi.x() > lo.x() && hi.z() > lo.z()) d = std::min(d, box_sdf(pl, lo, hi));
      }
    }
    return d;
  }

  double albedo_at(const Eigen::Vector3d& p) const override {
    const Eigen::Vector3d pl = R_.transpose() * (p - g_.center);
    if (pl.y() < 0.5 * g_.relief_m) return 0.75;  // mortar (bright) on the joint plane
    const int row = static_cast<int>(std::floor((pl.z() - g_.z_min) / g_.block_height_m));
    const double offset = (row & 1) ? 0.5 * g_.block_length_m : 0.0;
    const int k = static_cast<int>(std::floor((pl.x() - x0_ - offset) / g_.block_length_m));
    const double block = 0.3 + 0.3 * hash01(row, k, 3);
    return std::clamp(block + 0.12 * (value_noise(pl * 12.0) - 0.5), 0.0, 1.0);
  }

 private:
  bool slab_interval(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min, double t_max,
                     double* ta, double* tb) const {
    const Eigen::Vector3d lo(x0_, 0.0, g_.z_min), hi(x1_, g_.relief_m, g_.z_max);
    double t0 = t_min, t1 = t_max;
    for (int i = 0; i < 3; ++i) {
      if (std::abs(d[i]) < 1e-15) {
        if (o[i] < lo[i] || o[i] > hi[i]) return false;
        continue;
      }
      double a = (lo[i] - o[i]) / d[i], b = (hi[i] - o[i]) / d[i];
      if (a > b) std::swap(a, b);
      t0 = std::max(t0, a);
      t1 = std::min(t1, b);
      if (t0 > t1) return false;
    }
    *ta = t0, *tb = t1;
    return true;
  }

  // Block (lo/hi in local coordinates, clipped to the wall) of the running-bond cell that
  // contains (x, z), shifted by dr rows and dk blocks; cell_lo/hi: the cell with joints.
  void block_at(double x, double z, int dr, int dk, Eigen::Vector3d* lo, Eigen::Vector3d* hi,
                Eigen::Vector3d* cell_lo, Eigen::Vector3d* cell_hi) const {
    const int row = static_cast<int>(std::floor((z - g_.z_min) / g_.block_height_m)) + dr;
    const double offset = (row & 1) ? 0.5 * g_.block_length_m : 0.0;
    const int k = static_cast<int>(std::floor((x - x0_ - offset) / g_.block_length_m)) + dk;
    const double cx0 = x0_ + offset + k * g_.block_length_m,
                 cz0 = g_.z_min + row * g_.block_height_m;
    *cell_lo = Eigen::Vector3d(cx0, 0.0, cz0);
    *cell_hi = Eigen::Vector3d(cx0 + g_.block_length_m, g_.relief_m, cz0 + g_.block_height_m);
    const double half_joint = 0.5 * g_.joint_m;
    *lo =
        Eigen::Vector3d(std::max(cx0 + half_joint, x0_), 0.0, std::max(cz0 + half_joint, g_.z_min));
    *hi = Eigen::Vector3d(std::min(cx0 + g_.block_length_m - half_joint, x1_), g_.relief_m,
                          std::min(cz0 + g_.block_height_m - half_joint, g_.z_max));
  }

  ReliefWallGeometry g_;
  Eigen::Matrix3d R_;
  double x0_, x1_;
};

}  // namespace

double value_noise(const Eigen::Vector3d& p) {
  const Eigen::Vector3d f = p.array().floor();
  const Eigen::Vector3d r = p - f;
  const Eigen::Vector3d s = r.array() * r.array() * (3.0 - 2.0 * r.array());
  const int64_t x = static_cast<int64_t>(f.x()), y = static_cast<int64_t>(f.y()),
                z = static_cast<int64_t>(f.z());
  double corner[8];
  for (int c = 0; c < 8; ++c) corner[c] = hash01(x + (c & 1), y + ((c >> 1) & 1), z + (c >> 2));
  auto lerp = [](double a, double b, double w) { return a + (b - a) * w; };
  const double x00 = lerp(corner[0], corner[1], s.x()), x10 = lerp(corner[2], corner[3], s.x());
  const double x01 = lerp(corner[4], corner[5], s.x()), x11 = lerp(corner[6], corner[7], s.x());
  return lerp(lerp(x00, x10, s.y()), lerp(x01, x11, s.y()), s.z());
}

double Primitive::albedo_at(const Eigen::Vector3d& p) const {
  switch (material.texture) {
    case Texture::kConcrete:
      return std::clamp(material.albedo + 0.2 * (value_noise(p * 1.5) - 0.5) +
                            0.15 * (value_noise(p * 9.0) - 0.5),
                        0.0, 1.0);
    case Texture::kWater:
      return std::clamp(material.albedo + 0.08 * (value_noise(p * 0.7) - 0.5), 0.0, 1.0);
    case Texture::kSeabed:
      return std::clamp(material.albedo + 0.2 * (value_noise(p * 2.0) - 0.5), 0.0, 1.0);
    default:
      return material.albedo;
  }
}

std::unique_ptr<Primitive> make_plane(const Eigen::Vector3d& point, const Eigen::Vector3d& normal,
                                      const Material& material, const std::string& name) {
  auto p = std::make_unique<Plane>(point, normal);
  p->material = material;
  p->name = name;
  return p;
}

std::unique_ptr<Primitive> make_box(const Eigen::Vector3d& center, const Eigen::Matrix3d& R,
                                    const Eigen::Vector3d& half_extents, const Material& material,
                                    const std::string& name) {
  auto p = std::make_unique<Box>(center, R, half_extents);
  p->material = material;
  p->name = name;
  return p;
}

std::unique_ptr<Primitive> make_box_with_cavities(const Eigen::Vector3d& center,
                                                  const Eigen::Matrix3d& R,
                                                  const Eigen::Vector3d& half_extents,
                                                  const std::vector<Eigen::AlignedBox3d>& cavities,
                                                  const Material& material,
                                                  const std::string& name) {
  auto p = std::make_unique<CavityBox>(center, R, half_extents, cavities);
  p->material = material;
  p->name = name;
  return p;
}

std::unique_ptr<Primitive> make_cylinder(const Eigen::Vector3d& center, const Eigen::Matrix3d& R,
                                         double radius, double half_height,
                                         const Material& material, const std::string& name) {
  auto p = std::make_unique<Cylinder>(center, R, radius, half_height);
  p->material = material;
  p->name = name;
  return p;
}

std::unique_ptr<Primitive> make_relief_wall(const ReliefWallGeometry& geometry,
                                            const Material& material, const std::string& name) {
  auto p = std::make_unique<ReliefWall>(geometry);
  p->material = material;
  p->name = name;
  return p;
}

void AnalyticScene::add(std::unique_ptr<Primitive> primitive) {
  primitives_.push_back(std::move(primitive));
}

bool AnalyticScene::raycast(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_min,
                            double t_max, RayHit* hit) const {
  const Eigen::Vector3d inv(1.0 / dir.x(), 1.0 / dir.y(), 1.0 / dir.z());
  double best = t_max;
  int best_index = -1;
  Eigen::Vector3d best_normal = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < primitives_.size(); ++i) {
    const Primitive& prim = *primitives_[i];
    if (!prim.bounds.isEmpty()) {  // coarse cull: ray against the world AABB
      double t0 = t_min, t1 = best;
      bool miss = false;
      for (int a = 0; a < 3 && !miss; ++a) {
        double ta = (prim.bounds.min()[a] - origin[a]) * inv[a];
        double tb = (prim.bounds.max()[a] - origin[a]) * inv[a];
        if (ta > tb) std::swap(ta, tb);
        if (std::isnan(ta) || std::isnan(tb)) continue;  // parallel and on a face
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
        miss = t0 > t1;
      }
      if (miss) continue;
    }
    double t;
    Eigen::Vector3d normal;
    if (prim.intersect(origin, dir, t_min, best, &t, &normal) && t < best) {
      best = t;
      best_index = static_cast<int>(i);
      best_normal = normal;
    }
  }
  if (best_index < 0) return false;
  const Primitive& prim = *primitives_[best_index];
  hit->range_m = best;
  hit->normal = best_normal;
  hit->surface = best_index;
  hit->returns = prim.material.returns;
  hit->albedo = prim.albedo_at(origin + best * dir);
  return true;
}

double AnalyticScene::shade(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                            const RayHit* hit) const {
  static const Eigen::Vector3d kSun = Eigen::Vector3d(0.4, 0.3, 0.8).normalized();
  if (hit == nullptr) return std::clamp(0.7 + 0.25 * dir.z(), 0.0, 1.0);  // sky
  const double diffuse = std::max(0.0, hit->normal.dot(kSun));
  return std::clamp(hit->albedo * (0.35 + 0.65 * diffuse), 0.0, 1.0);
}

double AnalyticScene::distance_to_returning_surface(const Eigen::Vector3d& p) const {
  double best = kInf;
  for (const auto& prim : primitives_) {
    if (!prim->material.returns) continue;
    best = std::min(best, std::abs(prim->signed_distance(p)));
  }
  return best;
}

}  // namespace keel::sim
