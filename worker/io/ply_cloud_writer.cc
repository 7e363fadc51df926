#include "worker/io/ply_cloud_writer.h"

#include <stdexcept>
#include <string>

#include "worker/io/mesh_ply_binary_writer.h"

namespace keel::io {
namespace {

void check_optional_size(const char* name, size_t size, size_t expected) {
  if (size != 0 && size != expected) {
    throw std::invalid_argument("write_ply_cloud: PointCloud." + std::string(name) + " has " +
                                std::to_string(size) + " entries, expected 0 or " +
                                std::to_string(expected));
  }
}

}  // namespace

void write_ply_cloud(const std::filesystem::path& path, const PointCloud& cloud,
                     const std::vector<ScalarField>& point_fields) {
  const size_t n = cloud.size();
  check_optional_size("intensity", cloud.intensity.size(), n);
  check_optional_size("ring", cloud.ring.size(), n);
  check_optional_size("time_s", cloud.time_s.size(), n);
  check_scalar_fields(point_fields, n, {"x", "y", "z", "intensity", "ring", "time"});

  std::string header = "element vertex " + std::to_string(n) + "\n";
  header += "property float x\nproperty float y\nproperty float z\n";
  if (cloud.has_intensity()) header += "property float intensity\n";
  if (cloud.has_ring()) header += "property ushort ring\n";
  if (cloud.has_time()) header += "property float time\n";
  for (const auto& field : point_fields) header += "property float " + field.name + "\n";

  const size_t point_bytes = 12 + (cloud.has_intensity() ? 4 : 0) + (cloud.has_ring() ? 2 : 0) +
                             (cloud.has_time() ? 4 : 0) + 4 * point_fields.size();
  mesh_detail::PlyBinaryWriter writer(path);
  writer.begin(header, point_bytes * n);
  for (size_t i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) writer.put(cloud.xyz[i][c]);
    if (cloud.has_intensity()) writer.put(cloud.intensity[i]);
    if (cloud.has_ring()) writer.put(cloud.ring[i]);
    if (cloud.has_time()) writer.put(cloud.time_s[i]);
    for (const auto& field : point_fields) writer.put(field.values[i]);
  }
  writer.finish();
}

}  // namespace keel::io
