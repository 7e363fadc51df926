// Sanity report on a mesh before it is used as a CAD prior: it reports, never fails, so a
// job can go on with a slightly broken CAD model and say what it found.
#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <cstddef>
#include <string>
#include <vector>

#include "core/triangle_mesh.h"

namespace keel::io {

struct MeshCheckOptions {
  // A triangle whose area is below this fraction of (largest extent)^2 counts as zero area.
  double degenerate_relative_area = 1e-12;
  // Extents outside [min, max] suggest wrong units: a ship hull or bridge pier is metres to
  // a few hundred metres (the largest ships are ~460 m), so > 1 km is probably millimetres
  // and < 0.5 m kilometres (a 200 m hull in km is 0.2).
  double max_plausible_extent_m = 1000.0;
  double min_plausible_extent_m = 0.5;
};

struct MeshWarning {
  std::string kind;     // degenerate_faces, non_manifold_edges, boundary_edges, ...
  size_t count = 0;     // how many faces/edges/vertices it concerns (1 for units)
  std::string message;  // one sentence for the job log
};

struct MeshCheckReport {
  size_t num_vertices = 0;
  size_t num_faces = 0;
  size_t num_edges = 0;  // distinct undirected edges
  Eigen::Vector3d bbox_min = Eigen::Vector3d::Zero();
  Eigen::Vector3d bbox_max = Eigen::Vector3d::Zero();
  double largest_extent_m = 0.0;
  double surface_area_m2 = 0.0;     // sum of the triangle areas (faces with valid indices)
  size_t invalid_index_faces = 0;   // an index outside the vertex list (otherwise skipped)
  size_t repeated_index_faces = 0;  // a vertex index used twice in one face
  size_t zero_area_faces = 0;       // distinct indices, but (near) zero area
  size_t non_manifold_edges = 0;    // shared by more than two faces
  size_t boundary_edges = 0;        // used by exactly one face
  size_t inconsistent_edges = 0;    // two faces traverse it in the same direction
  size_t duplicate_faces = 0;       // same vertex set as an earlier face
  size_t unreferenced_vertices = 0;
  std::vector<MeshWarning> warnings;  // one per problem found, with its count

  size_t degenerate_faces() const {
    return invalid_index_faces + repeated_index_faces + zero_area_faces;
  }
  bool is_closed() const { return boundary_edges == 0 && non_manifold_edges == 0; }
  nlohmann::json to_json() const;
};

// Counts every problem listed in MeshCheckReport and adds a warning for each kind found.
MeshCheckReport check_mesh(const TriangleMesh& mesh, const MeshCheckOptions& options = {});

}  // namespace keel::io
