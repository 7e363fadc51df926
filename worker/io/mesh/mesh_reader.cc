#include "worker/io/mesh/mesh_reader.h"

#include <algorithm>
#include <cctype>

#include "worker/io/mesh/mesh_parse_util.h"

namespace keel::io {

TriangleMesh read_mesh(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (extension == ".ply") return read_ply_mesh(path);
  if (extension == ".obj") return read_obj_mesh(path);
  if (extension == ".stl") return read_stl_mesh(path);
  if (extension == ".off") return read_off_mesh(path);
  mesh_detail::fail(
      path, 0, "unknown mesh extension '" + extension + "' (expected .ply, .obj, .stl or .off)");
}

}  // namespace keel::io
