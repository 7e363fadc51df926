// Closed test meshes with known inside/outside: icosphere, box, L-shaped prism (non-convex)
// and a UV ellipsoid of any size (the 100k-triangle benchmark hull). All outward-oriented.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cmath>
#include <map>
#include <utility>

#include "core/triangle_mesh.h"

namespace keel::testing {

// Icosahedron subdivided `level` times, vertices pushed onto the sphere: 20 * 4^level faces.
inline TriangleMesh make_icosphere(int level, double radius = 1.0,
                                   const Eigen::Vector3d& center = Eigen::Vector3d::Zero()) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  TriangleMesh mesh;
  for (const auto& v :
       {Eigen::Vector3d(-1, t, 0), Eigen::Vector3d(1, t, 0), Eigen::Vector3d(-1, -t, 0),
        Eigen::Vector3d(1, -t, 0), Eigen::Vector3d(0, -1, t), Eigen::Vector3d(0, 1, t),
        Eigen::Vector3d(0, -1, -t), Eigen::Vector3d(0, 1, -t), Eigen::Vector3d(t, 0, -1),
        Eigen::Vector3d(t, 0, 1), Eigen::Vector3d(-t, 0, -1), Eigen::Vector3d(-t, 0, 1)}) {
    mesh.vertices.push_back(v.normalized());
  }
  mesh.faces = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<int, int>, int> midpoints;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      const auto it = midpoints.find(key);
      if (it != midpoints.end()) return it->second;
      mesh.vertices.push_back((mesh.vertices[a] + mesh.vertices[b]).normalized());
      const int index = static_cast<int>(mesh.vertices.size()) - 1;
      midpoints[key] = index;
      return index;
    };
    std::vector<Eigen::Vector3i> faces;
    for (const auto& f : mesh.faces) {
      const int ab = midpoint(f[0], f[1]), bc = midpoint(f[1], f[2]), ca = midpoint(f[2], f[0]);
      faces.insert(faces.end(), {{f[0], ab, ca}, {f[1], bc, ab}, {f[2], ca, bc}, {ab, bc, ca}});
    }
    mesh.faces = std::move(faces);
  }
  for (auto& v : mesh.vertices) v = center + radius * v;
  return mesh;
}

// Axis-aligned box, 8 vertices and 12 triangles.
inline TriangleMesh make_box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  TriangleMesh mesh;
  for (int i = 0; i < 8; ++i) {
    mesh.vertices.emplace_back(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(),
                               i & 4 ? hi.z() : lo.z());
  }
  // Quads counter-clockwise seen from outside, split into two triangles each.
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    mesh.faces.emplace_back(q[0], q[1], q[2]);
    mesh.faces.emplace_back(q[0], q[2], q[3]);
  }
  return mesh;
}

// The L-shaped polygon (0,0) (2,0) (2,1) (1,1) (1,2) (0,2) extruded over z in [0, 1]:
// non-convex, with a concave edge along x = y = 1.
inline TriangleMesh make_l_prism() {
  const double xy[6][2] = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
  TriangleMesh mesh;
  for (int z = 0; z < 2; ++z) {
    for (const auto& p : xy) mesh.vertices.emplace_back(p[0], p[1], z);
  }
  // Caps: a fan from the reflex corner 3 = (1,1) sees every other corner.
  const int fan[4][2] = {{4, 5}, {5, 0}, {0, 1}, {1, 2}};
  for (const auto& f : fan) {
    mesh.faces.emplace_back(3 + 6, f[0] + 6, f[1] + 6);  // top, normal +z
    mesh.faces.emplace_back(3, f[1], f[0]);              // bottom, normal -z
  }
  // Sides: the polygon is counter-clockwise, so (i, i+1, i+1 top) faces outward.
  for (int i = 0; i < 6; ++i) {
    const int j = (i + 1) % 6;
    mesh.faces.emplace_back(i, j, j + 6);
    mesh.faces.emplace_back(i, j + 6, i + 6);
  }
  return mesh;
}

inline bool inside_l_prism(const Eigen::Vector3d& p) {
  const bool in_polygon = (p.x() > 0 && p.x() < 2 && p.y() > 0 && p.y() < 1) ||
                          (p.x() > 0 && p.x() < 1 && p.y() > 0 && p.y() < 2);
  return in_polygon && p.z() > 0 && p.z() < 1;
}

// Ellipsoid from a longitude/latitude grid with pole fans: 2 * n_lon * (n_lat - 1) faces.
inline TriangleMesh make_uv_ellipsoid(int n_lon, int n_lat, const Eigen::Vector3d& radii) {
  TriangleMesh mesh;
  mesh.vertices.emplace_back(0, 0, radii.z());  // north pole
  for (int i = 1; i < n_lat; ++i) {
    const double theta = M_PI * i / n_lat;
    for (int j = 0; j < n_lon; ++j) {
      const double phi = 2 * M_PI * j / n_lon;
      mesh.vertices.emplace_back(radii.x() * std::sin(theta) * std::cos(phi),
                                 radii.y() * std::sin(theta) * std::sin(phi),
                                 radii.z() * std::cos(theta));
    }
  }
  mesh.vertices.emplace_back(0, 0, -radii.z());  // south pole
  const int south = static_cast<int>(mesh.vertices.size()) - 1;
  auto ring = [&](int i, int j) { return 1 + (i - 1) * n_lon + (j % n_lon); };
  for (int j = 0; j < n_lon; ++j) {
    mesh.faces.emplace_back(0, ring(1, j), ring(1, j + 1));
    mesh.faces.emplace_back(south, ring(n_lat - 1, j + 1), ring(n_lat - 1, j));
  }
  for (int i = 1; i + 1 < n_lat; ++i) {
    for (int j = 0; j < n_lon; ++j) {
      mesh.faces.emplace_back(ring(i, j), ring(i + 1, j), ring(i + 1, j + 1));
      mesh.faces.emplace_back(ring(i, j), ring(i + 1, j + 1), ring(i, j + 1));
    }
  }
  return mesh;
}

// A prism over the triangle (0,0) (1,0) (0.5,2) in the xz-plane, y in [0, 1]: its top edge
// has a 28 degree dihedral angle, where one face's normal gives the wrong side for points
// just outside (the case angle-weighted pseudonormals exist for).
inline TriangleMesh make_sharp_wedge() {
  TriangleMesh mesh;
  mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {0.5, 0, 2}, {0, 1, 0}, {1, 1, 0}, {0.5, 1, 2}};
  mesh.faces = {{0, 1, 2}, {3, 5, 4}, {0, 3, 4}, {0, 4, 1},
                {1, 4, 5}, {1, 5, 2}, {0, 2, 5}, {0, 5, 3}};
  return mesh;
}

// True when p is strictly inside a closed convex outward-oriented mesh.
inline bool inside_convex(const TriangleMesh& mesh, const Eigen::Vector3d& p) {
  for (const auto& f : mesh.faces) {
    const Eigen::Vector3d& a = mesh.vertices[f[0]];
    const Eigen::Vector3d n = (mesh.vertices[f[1]] - a).cross(mesh.vertices[f[2]] - a);
    if ((p - a).dot(n) >= 0) return false;
  }
  return true;
}

}  // namespace keel::testing
