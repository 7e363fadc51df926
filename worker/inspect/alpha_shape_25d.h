// 2.5D alpha shapes: line 13 of Algorithm 1, seed 001. "alpha-shapes using 2D Delaunay
// triangulation on the points' x, y coordinates as expressed in the camera frame. Each vertex
// in the 2D triangulation is then assigned the camera-relative z value" (section 3.2).
// We triangulate in the camera frame, as the paper does (not the hull's tangent plane): then
// every ray from the camera centre meets a shape at most about once, which Algorithm 2 relies on.
#pragma once

#include <Eigen/Core>

#include <vector>

#include "core/triangle_mesh.h"

namespace keel::inspect {

struct Shape25d {
  // Vertices in the camera frame (x, y of the triangulation, z kept from the input point).
  // Faces are oriented so that their normals point towards the camera (-z side), like the
  // outward normals of a hull seen from the camera.
  TriangleMesh mesh;
  // mesh.vertices[k] is points_camera[source_index[k]].
  std::vector<int> source_index;
};

// The REGULARIZED alpha shape (Edelsbrunner & Muecke) of the points' (x, y): the Delaunay
// triangles whose smallest empty circumscribing disc has radius <= alpha_m, i.e. CGAL
// Alpha_shape_2 INTERIOR faces with CGAL alpha = alpha_m^2 (CGAL's alpha is a squared radius).
// Points repeated in (x, y) keep the first one. Empty when no triangle qualifies (fewer than
// three points, collinear points, points farther apart than the alpha disc allows).
// Throws std::invalid_argument for non-finite points or alpha_m <= 0.
Shape25d alpha_shape_25d(const std::vector<Eigen::Vector3d>& points_camera, double alpha_m);

}  // namespace keel::inspect
