#include "worker/io/mesh/mesh_check.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <sstream>
#include <unordered_map>
#include <unordered_set>

namespace keel::io {
namespace {

uint64_t edge_key(int a, int b) {
  const auto lo = static_cast<uint32_t>(std::min(a, b));
  const auto hi = static_cast<uint32_t>(std::max(a, b));
  return (uint64_t{lo} << 32) | hi;
}

struct EdgeUse {
  int faces = 0;
  int forward = 0;  // uses in the direction lo -> hi
};

struct FaceKeyHash {
  size_t operator()(const std::array<int, 3>& k) const {
    size_t h = 0;
    for (const int v : k) h = h * 1000003u ^ std::hash<int>()(v);
    return h;
  }
};

std::string format_m(double value) {
  std::ostringstream out;
  out.precision(4);
  out << value;
  return out.str();
}

void bounding_box(const TriangleMesh& mesh, MeshCheckReport* report) {
  if (mesh.vertices.empty()) return;
  report->bbox_min = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  report->bbox_max = -report->bbox_min;
  for (const auto& v : mesh.vertices) {
    report->bbox_min = report->bbox_min.cwiseMin(v);
    report->bbox_max = report->bbox_max.cwiseMax(v);
  }
  report->largest_extent_m = (report->bbox_max - report->bbox_min).maxCoeff();
}

void count_faces_and_edges(const TriangleMesh& mesh, const MeshCheckOptions& options,
                           MeshCheckReport* report) {
  const int num_vertices = static_cast<int>(mesh.vertices.size());
  const double min_area =
      options.degenerate_relative_area * report->largest_extent_m * report->largest_extent_m;
  std::unordered_map<uint64_t, EdgeUse> edges;
  edges.reserve(mesh.faces.size() * 2);
  std::unordered_set<std::array<int, 3>, FaceKeyHash> seen_faces;
  seen_faces.reserve(mesh.faces.size());
  std::vector<bool> referenced(mesh.vertices.size(), false);
  for (const auto& f : mesh.faces) {
    if ((f.array() < 0).any() || (f.array() >= num_vertices).any()) {
      ++report->invalid_index_faces;
      continue;
    }
    for (int c = 0; c < 3; ++c) referenced[f[c]] = true;
    if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2]) {
      ++report->repeated_index_faces;
      continue;
    }
    const Eigen::Vector3d& a = mesh.vertices[f[0]];
    const double area = 0.5 * (mesh.vertices[f[1]] - a).cross(mesh.vertices[f[2]] - a).norm();
    if (area <= min_area) ++report->zero_area_faces;
    std::array<int, 3> key{f[0], f[1], f[2]};
    std::sort(key.begin(), key.end());
    if (!seen_faces.insert(key).second) {
      // Counted once, as a duplicate: its edges would otherwise also look non-manifold.
      ++report->duplicate_faces;
      continue;
    }
    report->surface_area_m2 += area;  // a duplicate face covers no new surface
    for (int c = 0; c < 3; ++c) {
      const int from = f[c];
      const int to = f[(c + 1) % 3];
      EdgeUse& use = edges[edge_key(from, to)];
      ++use.faces;
      if (from < to) ++use.forward;
    }
  }
  report->num_edges = edges.size();
  for (const auto& [key, use] : edges) {
    if (use.faces == 1) ++report->boundary_edges;
    if (use.faces > 2) ++report->non_manifold_edges;
    // A consistently oriented manifold edge is used once in each direction.
    if (use.faces == 2 && use.forward != 1) ++report->inconsistent_edges;
  }
  report->unreferenced_vertices =
      static_cast<size_t>(std::count(referenced.begin(), referenced.end(), false));
}

void add_warning(MeshCheckReport* report, const std::string& kind, size_t count,
                 const std::string& what) {
  if (count == 0) return;
  report->warnings.push_back({kind, count, std::to_string(count) + " " + what});
}

void add_warnings(const MeshCheckOptions& options, MeshCheckReport* report) {
  add_warning(report, "invalid_indices", report->invalid_index_faces,
              "faces with vertex indices outside the vertex list");
  add_warning(report, "degenerate_faces", report->repeated_index_faces,
              "degenerate faces use one vertex twice");
  add_warning(report, "degenerate_faces", report->zero_area_faces,
              "degenerate faces have zero area");
  add_warning(report, "non_manifold_edges", report->non_manifold_edges,
              "edges are shared by more than two faces (non-manifold)");
  add_warning(report, "boundary_edges", report->boundary_edges,
              "boundary edges: the mesh is not closed");
  add_warning(report, "inconsistent_orientation", report->inconsistent_edges,
              "edges join faces with opposite orientation (normals flip there)");
  add_warning(report, "duplicate_faces", report->duplicate_faces,
              "faces repeat the vertices of an earlier face");
  add_warning(report, "unreferenced_vertices", report->unreferenced_vertices,
              "vertices belong to no face");
  const double extent = report->largest_extent_m;
  if (report->num_vertices > 0 && extent > options.max_plausible_extent_m) {
    report->warnings.push_back({"units", 1,
                                "largest extent " + format_m(extent) + " m exceeds " +
                                    format_m(options.max_plausible_extent_m) +
                                    " m: are the coordinates in millimetres?"});
  } else if (report->num_vertices > 0 && extent < options.min_plausible_extent_m) {
    report->warnings.push_back({"units", 1,
                                "largest extent " + format_m(extent) + " m is below " +
                                    format_m(options.min_plausible_extent_m) +
                                    " m: are the coordinates in kilometres?"});
  }
}

}  // namespace

MeshCheckReport check_mesh(const TriangleMesh& mesh, const MeshCheckOptions& options) {
  MeshCheckReport report;
  report.num_vertices = mesh.vertices.size();
  report.num_faces = mesh.faces.size();
  bounding_box(mesh, &report);
  count_faces_and_edges(mesh, options, &report);
  add_warnings(options, &report);
  return report;
}

nlohmann::json MeshCheckReport::to_json() const {
  nlohmann::json warnings_json = nlohmann::json::array();
  for (const auto& w : warnings) {
    warnings_json.push_back({{"kind", w.kind}, {"count", w.count}, {"message", w.message}});
  }
  return {{"num_vertices", num_vertices},
          {"num_faces", num_faces},
          {"num_edges", num_edges},
          {"bbox_min", {bbox_min.x(), bbox_min.y(), bbox_min.z()}},
          {"bbox_max", {bbox_max.x(), bbox_max.y(), bbox_max.z()}},
          {"largest_extent_m", largest_extent_m},
          {"surface_area_m2", surface_area_m2},
          {"degenerate_faces", degenerate_faces()},
          {"invalid_index_faces", invalid_index_faces},
          {"repeated_index_faces", repeated_index_faces},
          {"zero_area_faces", zero_area_faces},
          {"non_manifold_edges", non_manifold_edges},
          {"boundary_edges", boundary_edges},
          {"inconsistent_edges", inconsistent_edges},
          {"duplicate_faces", duplicate_faces},
          {"unreferenced_vertices", unreferenced_vertices},
          {"closed", is_closed()},
          {"warnings", warnings_json}};
}

}  // namespace keel::io
