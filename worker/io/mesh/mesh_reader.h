// Reads CAD meshes (PLY, OBJ, STL, OFF) into a TriangleMesh.
//
// Keel parses these formats itself instead of using CGAL::IO::read_polygon_soup (CGAL 5.5):
// CGAL's readers return only a bool (details go to std::cerr when `verbose` is set), so a
// job could not say which line of which file is wrong, and they accept NaN coordinates
// silently. The formats are small; every error here names the file, and the line (text
// formats) or the element and byte offset (binary formats).
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>

#include "core/triangle_mesh.h"

namespace keel::io {

// A file that is not a valid mesh. what() = "<file>[:<line>]: <what is wrong>".
class MeshReadError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Dispatches on the extension (.ply .obj .stl .off, any case). Polygons become triangle
// fans. Throws MeshReadError for an unknown extension, an unreadable or malformed file,
// non-finite coordinates, out-of-range indices or a mesh without faces.
TriangleMesh read_mesh(const std::filesystem::path& path);

// PLY: ascii, binary_little_endian and binary_big_endian. Reads vertex x/y/z (any numeric
// type), optional nx/ny/nz and red/green/blue, and the face list `vertex_indices` (or
// `vertex_index`); other elements and properties are skipped.
TriangleMesh read_ply_mesh(const std::filesystem::path& path);

// OBJ: `v`, `vt`, `vn`, `f` with v, v/vt, v/vt/vn and v//vn corners, negative (relative)
// indices and polygons. Materials, groups and lines are ignored.
TriangleMesh read_obj_mesh(const std::filesystem::path& path);

// STL: ascii and binary. A file is binary when its size is 84 + 50 * (triangle count in
// the header), even when the header starts with "solid" (many CAD exporters do that).
// Identical corner positions are merged into one vertex, so the mesh is indexed.
TriangleMesh read_stl_mesh(const std::filesystem::path& path);

// OFF (also COFF, NOFF, CNOFF, STOFF): ascii only; vertex colours and normals are ignored.
TriangleMesh read_off_mesh(const std::filesystem::path& path);

}  // namespace keel::io
