#include "worker/inspect/alpha_shape_25d.h"

#include <CGAL/Alpha_shape_2.h>
#include <CGAL/Alpha_shape_face_base_2.h>
#include <CGAL/Alpha_shape_vertex_base_2.h>
#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace keel::inspect {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using VertexBase =
    CGAL::Alpha_shape_vertex_base_2<Kernel,
                                    CGAL::Triangulation_vertex_base_with_info_2<int, Kernel>>;
using FaceBase = CGAL::Alpha_shape_face_base_2<Kernel>;
using Tds = CGAL::Triangulation_data_structure_2<VertexBase, FaceBase>;
using Delaunay = CGAL::Delaunay_triangulation_2<Kernel, Tds>;
using AlphaShape = CGAL::Alpha_shape_2<Delaunay>;

void check_input(const std::vector<Eigen::Vector3d>& points, double alpha_m) {
  if (!(alpha_m > 0.0) || !std::isfinite(alpha_m)) {
    throw std::invalid_argument("alpha_shape_25d: alpha_m = " + std::to_string(alpha_m) +
                                "; expected a finite radius > 0 m");
  }
  for (size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite()) {
      throw std::invalid_argument("alpha_shape_25d: point " + std::to_string(i) +
                                  " is not finite; expected finite coordinates");
    }
  }
}

}  // namespace

Shape25d alpha_shape_25d(const std::vector<Eigen::Vector3d>& points_camera, double alpha_m) {
  check_input(points_camera, alpha_m);
  Shape25d shape;
  if (points_camera.size() < 3) return shape;

  std::vector<std::pair<Kernel::Point_2, int>> points_xy;
  points_xy.reserve(points_camera.size());
  for (size_t i = 0; i < points_camera.size(); ++i) {
    points_xy.emplace_back(Kernel::Point_2(points_camera[i].x(), points_camera[i].y()),
                           static_cast<int>(i));
  }
  Delaunay delaunay;
  delaunay.insert(points_xy.begin(), points_xy.end());
  if (delaunay.dimension() < 2) return shape;  // collinear
  // CGAL's alpha is the squared radius of the alpha disc.
  AlphaShape alpha_shape(delaunay, alpha_m * alpha_m, AlphaShape::REGULARIZED);

  std::vector<int> vertex_of_source(points_camera.size(), -1);
  auto vertex_index = [&](int source) {
    if (vertex_of_source[source] < 0) {
      vertex_of_source[source] = static_cast<int>(shape.mesh.vertices.size());
      shape.mesh.vertices.push_back(points_camera[source]);  // lifted: keeps its z (2.5D)
      shape.source_index.push_back(source);
    }
    return vertex_of_source[source];
  };
  for (auto face = alpha_shape.finite_faces_begin(); face != alpha_shape.finite_faces_end();
       ++face) {
    if (alpha_shape.classify(face) != AlphaShape::INTERIOR) continue;
    const int a = vertex_index(face->vertex(0)->info());
    const int b = vertex_index(face->vertex(1)->info());
    const int c = vertex_index(face->vertex(2)->info());
    // CGAL faces are counter-clockwise in (x, y), i.e. their normal is +z, away from the
    // camera; reversed so the normal faces the camera.
    shape.mesh.faces.emplace_back(a, c, b);
  }
  return shape;
}

}  // namespace keel::inspect
