#include "core/mesh_query.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>
#include <thread>
#include <unordered_map>

namespace keel {
namespace {

// Faces meeting at a dihedral angle above this are a crease (a chine, a box edge), not a
// tessellated curve: the smooth normals do not blend across it (30 degrees, as shading tools'
// auto-smooth default).
constexpr double kSmoothingCreaseAngle = 30.0 * M_PI / 180.0;

// Filtered exact predicates: a ray through a shared edge still hits one of its triangles.
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using CgalPoint = Kernel::Point_3;
using CgalTriangle = Kernel::Triangle_3;
using TriangleIterator = std::vector<CgalTriangle>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, TriangleIterator>;
using Traits = CGAL::AABB_traits<Kernel, Primitive>;
using Tree = CGAL::AABB_tree<Traits>;

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
  // Per face corner (3 f + c): the angle-weighted normal of the faces around the corner's
  // vertex within kSmoothingCreaseAngle of face f (compute_corner_normals()).
  std::vector<Eigen::Vector3d> corner_normals;
  std::vector<CgalTriangle> triangles;  // the tree's primitives point into this vector
  std::vector<int> triangle_face;       // tree triangle -> index into `faces`
  Tree tree;

  explicit Impl(const TriangleMesh& mesh);
  void compute_pseudonormals();
  void compute_corner_normals();
  double corner_angle(int face, int vertex) const;
  Eigen::Vector3d feature_normal(int face, const TrianglePoint& on_triangle) const;
  TrianglePoint on_face(int face, const Eigen::Vector3d& query) const;
  ClosestPoint result_on(int face, const TrianglePoint& on_triangle,
                         const Eigen::Vector3d& query) const;
  ClosestPoint closest_point(const Eigen::Vector3d& query) const;
  ClosestPoint closest_point_among(const Eigen::Vector3d& query,
                                   const std::vector<int>& among) const;
  ClosestPoint closest_point_sorted(const Eigen::Vector3d& query, const std::vector<int>& among,
                                    const std::vector<double>& lower_bounds_m,
                                    double bound_offset_m) const;
  std::vector<int> faces_within(const Eigen::Vector3d& center, double radius_m,
                                std::vector<double>* distances_m) const;
  class BallCollector;
  std::optional<RayHit> raycast(const Ray& ray) const;
  Eigen::Vector3d interpolated_normal(int face, const Eigen::Vector3d& p) const;
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
  compute_corner_normals();
  tree.insert(triangles.begin(), triangles.end());
  tree.build();
  // The distance queries' k-d tree is built on the triangles' centroids: CGAL's default, one
  // vertex of each triangle, puts a fan's faces that list the shared vertex first on one
  // point, and the k-d tree's recursion then overflowed the stack (10k such faces).
  std::vector<Tree::Point_and_primitive_id> centroids;
  centroids.reserve(triangles.size());
  for (auto t = triangles.cbegin(); t != triangles.cend(); ++t)
    centroids.emplace_back(CGAL::centroid(*t), t);
  tree.accelerate_distance_queries(centroids.begin(), centroids.end());
}

// Angle-weighted pseudonormals (Baerentzen & Aanaes 2005): with them the sign of
// (query - closest) . normal is the inside/outside answer also when the closest point is on
// an edge or a vertex, where a single face's normal can give the wrong sign.
void MeshQuery::Impl::compute_pseudonormals() {
  vertex_normals.assign(vertices.size(), Eigen::Vector3d::Zero());
  for (const int f : triangle_face) {
    const Eigen::Vector3i& face = faces[f];
    for (int c = 0; c < 3; ++c) {
      vertex_normals[face[c]] += corner_angle(f, face[c]) * face_normals[f];
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

// Smoothing groups with a crease angle, as in shading. Two faces sharing an edge are smooth
// there when their normals differ by at most kSmoothingCreaseAngle; the corners of smooth
// neighbours at the edge's two vertices join one group (union-find over the 3 F corners), and
// a corner's normal is its group's angle-weighted normal. So both faces of a smooth edge blend
// the same normals along it (continuous across it), a box's faces stay flat up to their
// corners, and the work is linear in the faces (a fan of 40k faces around one vertex too).
void MeshQuery::Impl::compute_corner_normals() {
  std::vector<size_t> parent(3 * faces.size());
  std::iota(parent.begin(), parent.end(), size_t{0});
  const auto root = [&parent](size_t c) {
    while (parent[c] != c) c = parent[c] = parent[parent[c]];  // path halving
    return c;
  };
  const auto corner = [this](int f, int v) {
    const Eigen::Vector3i& face = faces[f];
    return 3 * static_cast<size_t>(f) + (face[0] == v ? 0 : face[1] == v ? 1 : 2);
  };
  std::unordered_map<uint64_t, std::vector<int>> faces_at_edge;
  for (const int f : triangle_face) {
    for (int c = 0; c < 3; ++c)
      faces_at_edge[edge_key(faces[f][c], faces[f][(c + 1) % 3])].push_back(f);
  }
  const double min_cos = std::cos(kSmoothingCreaseAngle);
  for (const auto& [key, around] : faces_at_edge) {
    const int a = static_cast<int>(key >> 32), b = static_cast<int>(key & 0xffffffffu);
    for (size_t i = 0; i < around.size(); ++i) {
      for (size_t j = i + 1; j < around.size(); ++j) {  // 2 faces, more where non-manifold
        const int f = around[i], g = around[j];
        if (face_normals[f].dot(face_normals[g]) < min_cos) continue;  // a crease
        for (const int v : {a, b}) parent[root(corner(f, v))] = root(corner(g, v));
      }
    }
  }
  std::vector<Eigen::Vector3d> group_sum(parent.size(), Eigen::Vector3d::Zero());
  for (const int f : triangle_face) {
    for (int c = 0; c < 3; ++c)
      group_sum[root(3 * static_cast<size_t>(f) + c)] +=
          corner_angle(f, faces[f][c]) * face_normals[f];
  }
  corner_normals.assign(3 * faces.size(), Eigen::Vector3d::Zero());
  for (const int f : triangle_face) {
    for (int c = 0; c < 3; ++c) {
      const Eigen::Vector3d& sum = group_sum[root(3 * static_cast<size_t>(f) + c)];
      // A group can wrap round a vertex (a thin fin's rounded edge): keep the face's own
      // normal where the group's turns by more than 60 degrees from it.
      const double norm = sum.norm();
      corner_normals[3 * static_cast<size_t>(f) + c] =
          norm > 0 && sum.dot(face_normals[f]) > 0.5 * norm ? Eigen::Vector3d(sum / norm)
                                                            : face_normals[f];
    }
  }
}

double MeshQuery::Impl::corner_angle(int f, int v) const {
  const Eigen::Vector3i& face = faces[f];
  const int c = face[0] == v ? 0 : face[1] == v ? 1 : 2;
  const Eigen::Vector3d e1 = vertices[face[(c + 1) % 3]] - vertices[v];
  const Eigen::Vector3d e2 = vertices[face[(c + 2) % 3]] - vertices[v];
  return std::atan2(e1.cross(e2).norm(), e1.dot(e2));
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

TrianglePoint MeshQuery::Impl::on_face(int f, const Eigen::Vector3d& query) const {
  const Eigen::Vector3i& face = faces[f];
  return closest_on_triangle(query, vertices[face[0]], vertices[face[1]], vertices[face[2]]);
}

ClosestPoint MeshQuery::Impl::result_on(int f, const TrianglePoint& on_triangle,
                                        const Eigen::Vector3d& query) const {
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

ClosestPoint MeshQuery::Impl::closest_point(const Eigen::Vector3d& query) const {
  if (!query.allFinite()) throw std::invalid_argument("MeshQuery: query point is not finite");
  const auto [cgal_point, primitive] = tree.closest_point_and_primitive(to_cgal(query));
  (void)cgal_point;  // recomputed below together with the feature it lies on
  const int f = triangle_face[primitive - triangles.begin()];
  return result_on(f, on_face(f, query), query);
}

ClosestPoint MeshQuery::Impl::closest_point_among(const Eigen::Vector3d& query,
                                                  const std::vector<int>& among) const {
  if (!query.allFinite()) throw std::invalid_argument("MeshQuery: query point is not finite");
  if (among.empty()) throw std::invalid_argument("MeshQuery::closest_point_among: no face");
  int best_face = -1;
  TrianglePoint best{};
  double best_sq = std::numeric_limits<double>::infinity();
  for (const int f : among) {
    if (f < 0 || f >= static_cast<int>(faces.size()) || face_normals[f].squaredNorm() == 0) {
      throw std::invalid_argument("MeshQuery::closest_point_among: face " + std::to_string(f) +
                                  " is not a face of the tree");
    }
    const TrianglePoint candidate = on_face(f, query);
    const double sq = (query - candidate.point).squaredNorm();
    if (sq < best_sq) {
      best_sq = sq;
      best = candidate;
      best_face = f;
    }
  }
  return result_on(best_face, best, query);
}

// Faces sorted by lower_bounds_m[i] - bound_offset_m, a lower bound on their distance to the
// query: stop at the first that cannot be closer than the best so far.
ClosestPoint MeshQuery::Impl::closest_point_sorted(const Eigen::Vector3d& query,
                                                   const std::vector<int>& among,
                                                   const std::vector<double>& lower_bounds_m,
                                                   double bound_offset_m) const {
  int best_face = among.front();
  TrianglePoint best = on_face(best_face, query);
  double best_distance = (query - best.point).norm();
  for (size_t i = 1; i < among.size(); ++i) {
    if (lower_bounds_m[i] - bound_offset_m > best_distance) break;
    const TrianglePoint candidate = on_face(among[i], query);
    const double distance = (query - candidate.point).norm();
    if (distance < best_distance) {
      best_distance = distance;
      best = candidate;
      best_face = among[i];
    }
  }
  return result_on(best_face, best, query);
}

namespace {
struct Ball {
  Eigen::Vector3d center;
  double radius_sq;
};
}  // namespace

// Traversal traits for AABB_tree::traversal (CGAL's hook for custom queries): descend into
// the nodes whose box the ball touches and test each triangle with closest_on_triangle in
// plain doubles. A Bbox_3 query (all_intersected_primitives) spent most of its time in
// CGAL's filtered box-triangle predicate, whose exactness we do not need: the ball test
// below decides membership anyway (measured: 6 % of a `proposed` solve, issue 6).
class MeshQuery::Impl::BallCollector {
 public:
  BallCollector(const Impl& impl, std::vector<int>& faces, std::vector<double>* distances_m)
      : impl_(impl), faces_(faces), distances_m_(distances_m) {}
  constexpr bool go_further() const { return true; }
  void intersection(const Ball& ball, const Primitive& primitive) {
    const int f = impl_.triangle_face[primitive.id() - impl_.triangles.begin()];
    const double sq = (ball.center - impl_.on_face(f, ball.center).point).squaredNorm();
    if (sq > ball.radius_sq) return;
    faces_.push_back(f);
    if (distances_m_ != nullptr) distances_m_->push_back(std::sqrt(sq));
  }
  bool do_intersect(const Ball& ball, const CGAL::AABB_node<Traits>& node) const {
    const CGAL::Bbox_3& box = node.bbox();
    double sq = 0;
    for (int i = 0; i < 3; ++i) {
      const double below = box.min(i) - ball.center[i], above = ball.center[i] - box.max(i);
      if (below > 0) sq += below * below;
      if (above > 0) sq += above * above;
    }
    return sq <= ball.radius_sq;
  }

 private:
  const Impl& impl_;
  std::vector<int>& faces_;
  std::vector<double>* distances_m_;
};

std::vector<int> MeshQuery::Impl::faces_within(const Eigen::Vector3d& center, double radius_m,
                                               std::vector<double>* distances_m) const {
  if (!center.allFinite() || !(radius_m >= 0) || !std::isfinite(radius_m)) {
    throw std::invalid_argument("MeshQuery::faces_within: centre and radius must be finite");
  }
  std::vector<int> result;
  if (distances_m != nullptr) distances_m->clear();
  BallCollector collector(*this, result, distances_m);
  tree.traversal(Ball{center, radius_m * radius_m}, collector);
  return result;
}

// Phong normal at `p` on face `face`: its corner normals blended with p's barycentric
// coordinates.
Eigen::Vector3d MeshQuery::Impl::interpolated_normal(int face, const Eigen::Vector3d& p) const {
  const Eigen::Vector3i& f = faces[face];
  const Eigen::Vector3d &a = vertices[f[0]], &b = vertices[f[1]], &c = vertices[f[2]];
  const Eigen::Vector3d n = (b - a).cross(c - a);
  const double area2 = n.squaredNorm();
  const double wa = (c - b).cross(p - b).dot(n) / area2;
  const double wb = (a - c).cross(p - c).dot(n) / area2;
  const double wc = 1.0 - wa - wb;
  const size_t k = 3 * static_cast<size_t>(face);
  const Eigen::Vector3d blended =
      wa * corner_normals[k] + wb * corner_normals[k + 1] + wc * corner_normals[k + 2];
  const double norm = blended.norm();
  return norm > 1e-12 ? Eigen::Vector3d(blended / norm) : face_normals[face];
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
  result.interpolated_normal = interpolated_normal(result.face, hit);
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

std::vector<int> MeshQuery::faces_within(const Eigen::Vector3d& center, double radius_m,
                                         std::vector<double>* distances_m) const {
  return impl_->faces_within(center, radius_m, distances_m);
}

ClosestPoint MeshQuery::closest_point_among(const Eigen::Vector3d& query,
                                            const std::vector<int>& faces) const {
  return impl_->closest_point_among(query, faces);
}

LocalClosestPoint::LocalClosestPoint(const MeshQuery& mesh, const LocalClosestPointOptions& options)
    : mesh_(&mesh), options_(options) {
  if (!(options.move_bound_m > 0) || !(options.min_move_bound_m > 0) ||
      options.max_candidates < 1) {
    throw std::invalid_argument(
        "LocalClosestPoint: move_bound_m, min_move_bound_m and max_candidates must be positive");
  }
}

ClosestPoint LocalClosestPoint::closest_point(const Eigen::Vector3d& query) {
  if (!query.allFinite()) throw std::invalid_argument("MeshQuery: query point is not finite");
  if (!anchored_) return re_anchor(query, std::numeric_limits<double>::infinity());
  const double moved_m = (query - anchor_).norm();
  if (move_bound_m_ > 0 && moved_m <= move_bound_m_) {
    has_pending_ = false;  // back near the anchor: the jump was a rejected step
    ++cached_queries_;
    return mesh_->impl_->closest_point_sorted(query, candidates_, candidate_distances_m_, moved_m);
  }
  const double rho = options_.move_bound_m;
  if (move_bound_m_ > 0 && moved_m <= 2.0 * rho) return re_anchor(query, moved_m);  // drifting
  // A jump, or an anchor with too many faces around to cache (see the header).
  if (has_pending_ && (query - pending_).norm() <= rho) return re_anchor(query, moved_m);
  has_pending_ = true;
  pending_ = query;
  ++tree_queries_;
  return mesh_->closest_point(query);
}

ClosestPoint LocalClosestPoint::re_anchor(const Eigen::Vector3d& query, double moved_m) {
  ++tree_queries_;
  has_pending_ = false;
  const MeshQuery::Impl& impl = *mesh_->impl_;
  const double rho = options_.move_bound_m;
  // An upper bound u >= d0 suffices to collect every face within d0 + 2 rho: the faces within
  // u + 2 rho, among which the nearest is the exact closest one. After a moderate move the old
  // candidates give u without a closest-point query on the tree.
  double upper_m = std::numeric_limits<double>::infinity();
  if (move_bound_m_ > 0 && moved_m <= 2.0 * rho) {
    upper_m =
        impl.closest_point_sorted(query, candidates_, candidate_distances_m_, moved_m).distance_m;
  } else {
    upper_m = mesh_->closest_point(query).distance_m;
  }
  // Rounding of the distances (absolute, in metres): keep faces a hair beyond the bounds.
  const double slack = 1e-9 * (1.0 + upper_m);
  std::vector<double> distances;
  const std::vector<int> faces = impl.faces_within(query, upper_m + 2.0 * rho + slack, &distances);
  std::vector<size_t> order(faces.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](size_t a, size_t b) { return distances[a] < distances[b]; });
  if (order.empty()) {  // only by rounding: u is the distance to an existing face
    throw std::logic_error("LocalClosestPoint: no face within the distance bound");
  }
  const int nearest = faces[order.front()];
  const double d0 = distances[order.front()];
  const ClosestPoint closest = impl.result_on(nearest, impl.on_face(nearest, query), query);
  anchored_ = true;
  anchor_ = query;
  move_bound_m_ = rho;
  size_t keep = 0;
  while (keep < order.size() && distances[order[keep]] <= d0 + 2.0 * rho + slack) ++keep;
  const size_t max_candidates = static_cast<size_t>(options_.max_candidates);
  if (keep > max_candidates) {
    // Keep the faces nearer than the first one left out; rho' is half the gap from d0 to it,
    // so every face within d0 + 2 rho' of the anchor is still kept.
    const double cut = distances[order[max_candidates]];
    keep = 0;
    while (keep < order.size() && distances[order[keep]] < cut) ++keep;
    move_bound_m_ = 0.5 * (cut - d0) - slack;
    if (move_bound_m_ < options_.min_move_bound_m || keep == 0) {
      move_bound_m_ = 0.0;
      keep = 0;
    }
  }
  candidates_.resize(keep);
  candidate_distances_m_.resize(keep);
  for (size_t i = 0; i < keep; ++i) {
    candidates_[i] = faces[order[i]];
    candidate_distances_m_[i] = distances[order[i]];
  }
  return closest;
}

}  // namespace keel
