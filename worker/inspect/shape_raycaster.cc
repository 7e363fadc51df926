#include "worker/inspect/shape_raycaster.h"

#include <limits>
#include <stdexcept>

namespace keel::inspect {
namespace {

const TriangleMesh& checked_mesh(const Shape25d& shape) {
  if (shape.mesh.faces.empty()) {
    throw std::invalid_argument("ShapeRaycaster: the shape has no face; expected >= 1");
  }
  for (const Eigen::Vector3d& v : shape.mesh.vertices) {
    if (!(v.z() > 0.0)) {
      throw std::invalid_argument(
          "ShapeRaycaster: a shape vertex has z <= 0; expected every "
          "vertex in front of the camera");
    }
  }
  return shape.mesh;
}

}  // namespace

ShapeRaycaster::ShapeRaycaster(const Shape25d& shape) : query_(checked_mesh(shape)) {
  image_min_.setConstant(std::numeric_limits<double>::infinity());
  image_max_ = -image_min_;
  for (const Eigen::Vector3d& v : shape.mesh.vertices) {
    const Eigen::Vector2d image = v.head<2>() / v.z();
    image_min_ = image_min_.cwiseMin(image);
    image_max_ = image_max_.cwiseMax(image);
  }
}

std::optional<Eigen::Vector3d> ShapeRaycaster::intersect(const Eigen::Vector3d& vertex_camera,
                                                         double max_behind_vertex_m) const {
  // A ray towards a point with z <= 0 never reaches the shape (z > 0 everywhere).
  if (!(vertex_camera.z() > 0.0)) return std::nullopt;
  const Eigen::Vector2d image = vertex_camera.head<2>() / vertex_camera.z();
  if ((image.array() < image_min_.array()).any() || (image.array() > image_max_.array()).any()) {
    return std::nullopt;
  }
  keel::Ray ray;  // line 8: make_ray(pose, V_n[i])
  ray.origin = Eigen::Vector3d::Zero();
  ray.direction = vertex_camera;
  ray.max_range_m = vertex_camera.norm() + max_behind_vertex_m;
  const std::optional<keel::RayHit> hit = query_.raycast(ray);  // lines 9-10
  if (!hit) return std::nullopt;
  return hit->point;
}

}  // namespace keel::inspect
