// Scenes made of analytic primitives (planes, oriented boxes, capped cylinders and
// cinder-block relief walls) with exact ray intersection. The USV scenarios cast ~130 M lidar
// rays per mission: a generic triangle BVH would be several times slower than these closed
// forms behind a per-primitive bounding-box cull.
#pragma once

#include <Eigen/Geometry>

#include <memory>
#include <string>
#include <vector>

#include "tests/sim/sim_world.h"

namespace keel::sim {

enum class Texture { kPlain, kConcrete, kCinder, kWater, kSeabed };

struct Material {
  double albedo = 0.5;
  bool returns = true;  // false: absorbs range sensors (the water surface)
  Texture texture = Texture::kPlain;
};

class Primitive {
 public:
  virtual ~Primitive() = default;
  // Nearest entering intersection with t in [t_min, t_max]; normal in world.
  virtual bool intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_min,
                         double t_max, double* t, Eigen::Vector3d* normal) const = 0;
  // Signed distance (negative inside); planes: distance to the plane.
  virtual double signed_distance(const Eigen::Vector3d& p_world) const = 0;
  // Albedo at a surface point (texture), in [0, 1].
  virtual double albedo_at(const Eigen::Vector3d& p_world) const;

  Material material;
  Eigen::AlignedBox3d bounds;  // world AABB; empty = unbounded (planes)
  std::string name;
};

// Infinite plane through `point` with unit `normal`.
std::unique_ptr<Primitive> make_plane(const Eigen::Vector3d& point, const Eigen::Vector3d& normal,
                                      const Material& material, const std::string& name);
// Box with centre, rotation R_world_box and half extents.
std::unique_ptr<Primitive> make_box(const Eigen::Vector3d& center,
                                    const Eigen::Matrix3d& R_world_box,
                                    const Eigen::Vector3d& half_extents, const Material& material,
                                    const std::string& name);
// Box as make_box, with box-shaped cavities cut out of it (spalled concrete): each cavity is
// an axis-aligned box [lo, hi] in the box's local frame that opens through one of its faces
// (it reaches past that face and stays inside the others). A ray entering the box through a
// cavity's mouth meets the cavity's floor or walls instead.
std::unique_ptr<Primitive> make_box_with_cavities(const Eigen::Vector3d& center,
                                                  const Eigen::Matrix3d& R_world_box,
                                                  const Eigen::Vector3d& half_extents,
                                                  const std::vector<Eigen::AlignedBox3d>& cavities,
                                                  const Material& material,
                                                  const std::string& name);
// Capped cylinder along the local z axis of R_world_cylinder.
std::unique_ptr<Primitive> make_cylinder(const Eigen::Vector3d& center,
                                         const Eigen::Matrix3d& R_world_cylinder, double radius,
                                         double half_height, const Material& material,
                                         const std::string& name);

struct ReliefWallGeometry {
  // Local frame: x along the wall, y out of the relief face, z up. Face centre at `center`.
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  double yaw_rad = 0.0;              // rotation of the local frame about world z
  double length_m = 40.0;            // along x
  double z_min = -6.0, z_max = 3.0;  // local z extent (relative to center)
  double thickness_m = 1.0;          // wall body behind the face
  double block_length_m = 0.4;       // cinder block pitch along x (joint included)
  double block_height_m = 0.2;       // pitch along z
  double joint_m = 0.015;            // mortar joint width
  double relief_m = 0.04;            // how far blocks stand out of the mortar plane
};
std::unique_ptr<Primitive> make_relief_wall(const ReliefWallGeometry& geometry,
                                            const Material& material, const std::string& name);

class AnalyticScene : public SimWorld {
 public:
  void add(std::unique_ptr<Primitive> primitive);
  bool raycast(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_min,
               double t_max, RayHit* hit) const override;
  double shade(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
               const RayHit* hit) const override;
  // Unsigned distance to the nearest range-returning surface (closed-form SDFs; test oracle).
  double distance_to_returning_surface(const Eigen::Vector3d& p_world) const;
  const std::vector<std::unique_ptr<Primitive>>& primitives() const { return primitives_; }

 private:
  std::vector<std::unique_ptr<Primitive>> primitives_;
};

// Smooth 3D value noise in [0, 1] (hash lattice, smoothstep interpolation).
double value_noise(const Eigen::Vector3d& p);

}  // namespace keel::sim
