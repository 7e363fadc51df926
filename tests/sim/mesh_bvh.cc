#include "tests/sim/mesh_bvh.h"

#include <algorithm>
#include <cmath>

namespace keel::sim {
namespace {

// Moller-Trumbore ray-triangle intersection, both faces.
bool moller_trumbore(const Eigen::Vector3d& v0, const Eigen::Vector3d& v1,
                     const Eigen::Vector3d& v2, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                     double* t, double* b1, double* b2) {
  const Eigen::Vector3d e1 = v1 - v0, e2 = v2 - v0;
  const Eigen::Vector3d pvec = d.cross(e2);
  const double det = e1.dot(pvec);
  if (std::abs(det) < 1e-18) return false;
  const double inv = 1.0 / det;
  const Eigen::Vector3d tvec = o - v0;
  const double u = tvec.dot(pvec) * inv;
  if (u < 0.0 || u > 1.0) return false;
  const Eigen::Vector3d qvec = tvec.cross(e1);
  const double v = d.dot(qvec) * inv;
  if (v < 0.0 || u + v > 1.0) return false;
  *t = e2.dot(qvec) * inv;
  *b1 = u, *b2 = v;
  return true;
}

bool ray_box(const Eigen::AlignedBox3d& box, const Eigen::Vector3d& o, const Eigen::Vector3d& inv,
             double t_min, double t_max, double* t_enter) {
  double t0 = t_min, t1 = t_max;
  for (int a = 0; a < 3; ++a) {
    double ta = (box.min()[a] - o[a]) * inv[a], tb = (box.max()[a] - o[a]) * inv[a];
    if (ta > tb) std::swap(ta, tb);
    if (std::isnan(ta) || std::isnan(tb)) continue;
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  *t_enter = t0;
  return true;
}

}  // namespace

MeshBvh::MeshBvh(const TriangleMesh& mesh) : mesh_(mesh) {
  const int n = static_cast<int>(mesh_.faces.size());
  centroids_.resize(n);
  normals_.resize(n);
  order_.resize(n);
  for (int i = 0; i < n; ++i) {
    const auto& f = mesh_.faces[i];
    const Eigen::Vector3d &a = mesh_.vertices[f[0]], &b = mesh_.vertices[f[1]],
                          &c = mesh_.vertices[f[2]];
    centroids_[i] = (a + b + c) / 3.0;
    const Eigen::Vector3d cross = (b - a).cross(c - a);
    normals_[i] = cross.norm() > 0 ? Eigen::Vector3d(cross.normalized()) : Eigen::Vector3d::UnitZ();
    order_[i] = i;
  }
  nodes_.reserve(n + 1);
  if (n > 0) build(0, n);
}

int MeshBvh::build(int begin, int end) {
  const int index = static_cast<int>(nodes_.size());
  nodes_.emplace_back();
  Eigen::AlignedBox3d box, centroid_box;
  for (int i = begin; i < end; ++i) {
    const auto& f = mesh_.faces[order_[i]];
    for (int k = 0; k < 3; ++k) box.extend(mesh_.vertices[f[k]]);
    centroid_box.extend(centroids_[order_[i]]);
  }
  nodes_[index].box = box;
  if (end - begin <= 4) {
    nodes_[index].first = begin;
    nodes_[index].count = end - begin;
    return index;
  }
  int axis;
  centroid_box.sizes().maxCoeff(&axis);
  const int mid = (begin + end) / 2;
  std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                   [&](int a, int b) { return centroids_[a][axis] < centroids_[b][axis]; });
  const int left = build(begin, mid);
  const int right = build(mid, end);
  nodes_[index].first = left;
  nodes_[index].count = -right;  // negative marks an inner node; right > 0 always
  return index;
}

bool MeshBvh::hit_triangle(int tri, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                           double t_min, double t_max, MeshHit* hit) const {
  const auto& f = mesh_.faces[tri];
  double t, b1, b2;
  if (!moller_trumbore(mesh_.vertices[f[0]], mesh_.vertices[f[1]], mesh_.vertices[f[2]], o, d, &t,
                       &b1, &b2))
    return false;
  if (t < t_min || t > t_max) return false;
  hit->t = t, hit->triangle = tri, hit->b1 = b1, hit->b2 = b2;
  return true;
}

bool MeshBvh::raycast(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min,
                      double t_max, MeshHit* hit) const {
  if (nodes_.empty()) return false;
  const Eigen::Vector3d inv(1.0 / d.x(), 1.0 / d.y(), 1.0 / d.z());
  int stack[128];
  int top = 0;
  stack[top++] = 0;
  bool found = false;
  double best = t_max;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    double t_enter;
    if (!ray_box(node.box, o, inv, t_min, best, &t_enter)) continue;
    if (node.count > 0) {
      for (int i = node.first; i < node.first + node.count; ++i) {
        if (hit_triangle(order_[i], o, d, t_min, best, hit)) {
          best = hit->t;
          found = true;
        }
      }
      continue;
    }
    const int left = node.first, right = -node.count;
    double tl = 0, tr = 0;
    const bool hl = ray_box(nodes_[left].box, o, inv, t_min, best, &tl);
    const bool hr = ray_box(nodes_[right].box, o, inv, t_min, best, &tr);
    // Push the farther child first so the nearer one is visited first.
    if (hl && hr) {
      if (tl < tr) {
        stack[top++] = right;
        stack[top++] = left;
      } else {
        stack[top++] = left;
        stack[top++] = right;
      }
    } else if (hl) {
      stack[top++] = left;
    } else if (hr) {
      stack[top++] = right;
    }
  }
  return found;
}

bool raycast_brute_force(const TriangleMesh& mesh, const Eigen::Vector3d& o,
                         const Eigen::Vector3d& d, double t_min, double t_max, MeshHit* hit) {
  bool found = false;
  for (size_t i = 0; i < mesh.faces.size(); ++i) {
    const auto& f = mesh.faces[i];
    double t, b1, b2;
    if (moller_trumbore(mesh.vertices[f[0]], mesh.vertices[f[1]], mesh.vertices[f[2]], o, d, &t,
                        &b1, &b2) &&
        t >= t_min && t <= t_max) {
      t_max = t;
      *hit = MeshHit{t, static_cast<int>(i), b1, b2};
      found = true;
    }
  }
  return found;
}

}  // namespace keel::sim
