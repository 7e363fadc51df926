#include "worker/ba/mesh_query.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <thread>
#include <unordered_map>

namespace keel::ba {
namespace {

// Filtered exact predicates: a ray through a shared edge still hits one of its triangles.
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using CgalPoint = Kernel::Point_3;
using CgalTriangle = Kernel::Triangle_3;
using TriangleIterator = std::vector<CgalTriangle>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, TriangleIterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

CgalPoint to_cgal(const Eigen::Vector3d& p) { return CgalPoint(p.x(), p.y(), p.z()); }
Eigen::Vector3d to_eigen(const CgalPoint& p) { return {p.x(), p.y(), p.z()}; }

uint64_t edge_key(int a, int b) {
  const auto lo = static_cast<uint32_t>(std::min(a, b));
  const auto hi = static_cast<uint32_t>(std::max(a, b));
  return (uint64_t{lo} << 32) | hi;
}

struct TrianglePoint {
  Eigen::Vector3d point;
  MeshFeature feature;
  int index;  // corner 0..2 for a vertex; edge 0 = (0,1), 1 = (1,2), 2 = (2,0)
};

// Closest point on triangle abc to p and the feature (Voronoi region) it lies in; Ericson,
// Real-Time Collision Detection, 5.1.5. Regions come from sign tests, so a point beyond an
// edge is classified as on that edge exactly, not by a tolerance.
TrianglePoint closest_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                  const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return {a, MeshFeature::kVertex, 0};
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return {b, MeshFeature::kVertex, 1};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return {a + d1 / (d1 - d3) * ab, MeshFeature::kEdge, 0};
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return {c, MeshFeature::kVertex, 2};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return {a + d2 / (d2 - d6) * ac, MeshFeature::kEdge, 2};
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {b + w * (c - b), MeshFeature::kEdge, 1};
  }
  const double denom = 1.0 / (va + vb + vc);
  return {a + ab * (vb * denom) + ac * (vc * denom), MeshFeature::kFace, 0};
}

template <typename Function>
void parallel_for(size_t n, int num_threads, const Function& function) {
  const size_t threads = std::clamp<size_t>(num_threads, 1, std::max<size_t>(n, 1));
  if (threads == 1) {
    for (size_t i = 0; i < n; ++i) function(i);
    return;
  }
  std::vector<std::thread> workers;
  for (size_t t = 0; t < threads; ++t) {
    workers.emplace_back([&, t] {
      for (size_t i = t; i < n; i += threads) function(i);
    });
  }
  for (auto& worker : workers) worker.join();
}

}  // namespace

struct MeshQuery::Impl {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3i> faces;
  std::vector<Eigen::Vector3d> face_normals;                   // unit; zero for degenerate faces
  std::vector<Eigen::Vector3d> vertex_normals;                 // angle-weighted pseudonormals, unit
  std::unordered_map<uint64_t, Eigen::Vector3d> edge_normals;  // sum of face normals, unit
  std::vector<CgalTriangle> triangles;  // the tree's primitives point into this vector
  std::vector<int> triangle_face;       // tree triangle -> index into `faces`
  Tree tree;

  explicit Impl(const TriangleMesh& mesh);
  void compute_pseudonormals();
  Eigen::Vector3d feature_normal(int face, const TrianglePoint& on_triangle) const;
  ClosestPoint closest_point(const Eigen::Vector3d& query) const;
  std::optional<RayHit> raycast(const Ray& ray) const;
};

MeshQuery::Impl::Impl(const TriangleMesh& mesh) : vertices(mesh.vertices), faces(mesh.faces) {
  const int num_vertices = static_cast<int>(vertices.size());
  face_normals.assign(faces.size(), Eigen::Vector3d::Zero());
  for (size_t f = 0; f < faces.size(); ++f) {
    const Eigen::Vector3i& face = faces[f];
    if ((face.array() < 0).any() || (face.array() >= num_vertices).any()) {
      throw std::invalid_argument("MeshQuery: face " + std::to_string(f) +
                                  " has a vertex index outside [0, " +
                                  std::to_string(num_vertices) + ")");
    }
    const Eigen::Vector3d& a = vertices[face[0]];
    const Eigen::Vector3d& b = vertices[face[1]];
    const Eigen::Vector3d& c = vertices[face[2]];
    const Eigen::Vector3d cross = (b - a).cross(c - a);
    const double scale = std::max({(b - a).squaredNorm(), (c - a).squaredNorm(), 1e-300});
    // Zero-area faces have no normal and no interior: leave them to their neighbours.
    if (!cross.allFinite() || cross.norm() <= 1e-14 * scale) continue;
    face_normals[f] = cross.normalized();
    triangles.emplace_back(to_cgal(a), to_cgal(b), to_cgal(c));
    triangle_face.push_back(static_cast<int>(f));
  }
  if (triangles.empty()) throw std::invalid_argument("MeshQuery: the mesh has no face with area");
  compute_pseudonormals();
  tree.insert(triangles.begin(), triangles.end());
  tree.build();
  tree.accelerate_distance_queries();
}

// Angle-weighted pseudonormals (Baerentzen & Aanaes 2005): with them the sign of
// (query - closest) . normal is the inside/outside answer also when the closest point is on
// an edge or a vertex, where a single face's normal can give the wrong sign.
void MeshQuery::Impl::compute_pseudonormals() {
  vertex_normals.assign(vertices.size(), Eigen::Vector3d::Zero());
  for (const int f : triangle_face) {
    const Eigen::Vector3i& face = faces[f];
    for (int c = 0; c < 3; ++c) {
      const Eigen::Vector3d& p = vertices[face[c]];
      const Eigen::Vector3d e1 = vertices[face[(c + 1) % 3]] - p;
      const Eigen::Vector3d e2 = vertices[face[(c + 2) % 3]] - p;
      const double angle = std::atan2(e1.cross(e2).norm(), e1.dot(e2));
      vertex_normals[face[c]] += angle * face_normals[f];
      // Eigen vectors are not zero-initialized: insert an explicit zero first.
      const uint64_t key = edge_key(face[c], face[(c + 1) % 3]);
      edge_normals.try_emplace(key, Eigen::Vector3d::Zero()).first->second += face_normals[f];
    }
  }
  for (auto& n : vertex_normals) {
    if (n.norm() > 0) n.normalize();
  }
  for (auto& [key, n] : edge_normals) {
    if (n.norm() > 0) n.normalize();
  }
}

Eigen::Vector3d MeshQuery::Impl::feature_normal(int f, const TrianglePoint& on_triangle) const {
  const Eigen::Vector3i& face = faces[f];
  Eigen::Vector3d normal = face_normals[f];
  if (on_triangle.feature == MeshFeature::kVertex) {
    normal = vertex_normals[face[on_triangle.index]];
  } else if (on_triangle.feature == MeshFeature::kEdge) {
    normal = edge_normals.at(edge_key(face[on_triangle.index], face[(on_triangle.index + 1) % 3]));
  }
  // Opposite faces (a sheet folded onto itself) cancel; fall back to the face's own normal.
  return normal.squaredNorm() > 0.5 ? normal : face_normals[f];
}

ClosestPoint MeshQuery::Impl::closest_point(const Eigen::Vector3d& query) const {
  if (!query.allFinite()) throw std::invalid_argument("MeshQuery: query point is not finite");
  const auto [cgal_point, primitive] = tree.closest_point_and_primitive(to_cgal(query));
  (void)cgal_point;  // recomputed below together with the feature it lies on
  const int f = triangle_face[primitive - triangles.begin()];
  const Eigen::Vector3i& face = faces[f];
  const TrianglePoint on_triangle =
      closest_on_triangle(query, vertices[face[0]], vertices[face[1]], vertices[face[2]]);
  ClosestPoint result;
  result.point = on_triangle.point;
  result.face = f;
  result.feature = on_triangle.feature;
  result.distance_m = (query - on_triangle.point).norm();
  result.normal = feature_normal(f, on_triangle);
  const double side = (query - on_triangle.point).dot(result.normal);
  result.signed_distance_m = side < 0 ? -result.distance_m : result.distance_m;
  return result;
}

std::optional<RayHit> MeshQuery::Impl::raycast(const Ray& ray) const {
  const double length = ray.direction.norm();
  if (!(length > 0) || !ray.direction.allFinite() || !ray.origin.allFinite()) {
    throw std::invalid_argument("MeshQuery::raycast: direction must be finite and non-zero");
  }
  const Eigen::Vector3d direction = ray.direction / length;
  const double min_range = std::max(ray.min_range_m, 0.0);
  if (ray.max_range_m < min_range) return std::nullopt;
  const Eigen::Vector3d start = ray.origin + min_range * direction;
  const Kernel::Ray_3 cgal_ray(to_cgal(start),
                               Kernel::Vector_3(direction.x(), direction.y(), direction.z()));
  const auto intersection = tree.first_intersection(cgal_ray);
  if (!intersection) return std::nullopt;
  Eigen::Vector3d hit;
  if (const auto* point = boost::get<CgalPoint>(&intersection->first)) {
    hit = to_eigen(*point);
  } else if (const auto* segment = boost::get<Kernel::Segment_3>(&intersection->first)) {
    // The ray runs inside the triangle's plane: it enters at the nearer end.
    const Eigen::Vector3d p = to_eigen(segment->source()), q = to_eigen(segment->target());
    hit = (p - start).norm() <= (q - start).norm() ? p : q;
  } else {
    return std::nullopt;
  }
  RayHit result;
  result.distance_m = min_range + (hit - start).dot(direction);
  if (result.distance_m > ray.max_range_m) return std::nullopt;
  result.point = hit;
  result.face = triangle_face[intersection->second - triangles.begin()];
  result.face_normal = face_normals[result.face];
  return result;
}

MeshQuery::MeshQuery(const TriangleMesh& mesh) : impl_(std::make_unique<Impl>(mesh)) {}
MeshQuery::~MeshQuery() = default;
MeshQuery::MeshQuery(MeshQuery&&) noexcept = default;
MeshQuery& MeshQuery::operator=(MeshQuery&&) noexcept = default;

ClosestPoint MeshQuery::closest_point(const Eigen::Vector3d& query) const {
  return impl_->closest_point(query);
}

double MeshQuery::signed_distance(const Eigen::Vector3d& query) const {
  return impl_->closest_point(query).signed_distance_m;
}

std::optional<RayHit> MeshQuery::raycast(const Ray& ray) const { return impl_->raycast(ray); }

namespace {
// Validate up front: an exception must not escape a worker thread.
void check_finite(const std::vector<Eigen::Vector3d>& queries) {
  for (size_t i = 0; i < queries.size(); ++i) {
    if (!queries[i].allFinite()) {
      throw std::invalid_argument("MeshQuery: query point " + std::to_string(i) + " is not finite");
    }
  }
}
}  // namespace

std::vector<ClosestPoint> MeshQuery::closest_points(const std::vector<Eigen::Vector3d>& queries,
                                                    int num_threads) const {
  check_finite(queries);
  std::vector<ClosestPoint> results(queries.size());
  parallel_for(queries.size(), num_threads,
               [&](size_t i) { results[i] = impl_->closest_point(queries[i]); });
  return results;
}

std::vector<double> MeshQuery::signed_distances(const std::vector<Eigen::Vector3d>& queries,
                                                int num_threads) const {
  check_finite(queries);
  std::vector<double> results(queries.size());
  parallel_for(queries.size(), num_threads,
               [&](size_t i) { results[i] = impl_->closest_point(queries[i]).signed_distance_m; });
  return results;
}

std::vector<std::optional<RayHit>> MeshQuery::raycasts(const std::vector<Ray>& rays,
                                                       int num_threads) const {
  // Validate up front: an exception must not escape a worker thread.
  for (size_t i = 0; i < rays.size(); ++i) {
    if (!(rays[i].direction.norm() > 0) || !rays[i].direction.allFinite() ||
        !rays[i].origin.allFinite()) {
      throw std::invalid_argument("MeshQuery::raycasts: ray " + std::to_string(i) +
                                  " has a zero or non-finite direction or origin");
    }
  }
  std::vector<std::optional<RayHit>> results(rays.size());
  parallel_for(rays.size(), num_threads, [&](size_t i) { results[i] = impl_->raycast(rays[i]); });
  return results;
}

size_t MeshQuery::num_faces() const { return impl_->triangles.size(); }

}  // namespace keel::ba
