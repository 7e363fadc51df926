// make_ray / intersects_with / intersection of Algorithm 2 (lines 8-10, seed 001): the ray from
// the camera centre towards a CAD vertex, against one 2.5D shape in that camera's frame.
#pragma once

#include <Eigen/Core>

#include <optional>

#include "core/mesh_query.h"
#include "worker/inspect/alpha_shape_25d.h"

namespace keel::inspect {

class ShapeRaycaster {
 public:
  // `shape` must have at least one face and all vertices in front of the camera (z > 0), as
  // detect_shapes() guarantees; std::invalid_argument otherwise.
  explicit ShapeRaycaster(const Shape25d& shape);

  // p^i: the first point where the ray from the camera centre (the origin) through
  // `vertex_camera` meets the shape, if it does so no farther than max_behind_vertex_m beyond
  // the vertex (0: the segment camera centre -> vertex of section 3.3).
  std::optional<Eigen::Vector3d> intersect(const Eigen::Vector3d& vertex_camera,
                                           double max_behind_vertex_m) const;

 private:
  keel::MeshQuery query_;
  // Bounding box of the shape's vertices in normalised image coordinates (x/z, y/z). With all
  // vertices in front of the camera, a ray can only meet the shape inside it: a cheap test that
  // skips the tree for most of the vertices within view range.
  Eigen::Vector2d image_min_;
  Eigen::Vector2d image_max_;
};

}  // namespace keel::inspect
