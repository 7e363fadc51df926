#include "worker/io/cloud/ply_cloud_writer.h"

#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/replaced_file.h"

namespace keel::io {
namespace {

void check_optional_size(const char* name, size_t size, size_t expected) {
  if (size != 0 && size != expected) {
    throw std::invalid_argument("write_ply_cloud: PointCloud." + std::string(name) + " has " +
                                std::to_string(size) + " entries, expected 0 or " +
                                std::to_string(expected));
  }
}

// Points per chunk written: the body streams through a buffer of ~1 MB instead of being built
// whole in memory (a 14 M-point combined map would take 230 MB).
constexpr size_t kChunkPoints = 1 << 16;

template <typename T>
void put(char*& at, T value) {
  std::memcpy(at, &value, sizeof(T));  // little endian, as are Keel's hosts
  at += sizeof(T);
}

// The optional properties the (concatenated) cloud carries: each one every non-empty part has.
struct Properties {
  bool intensity = true, ring = true, time = true;
};

Properties properties_of(const std::vector<const PointCloud*>& parts) {
  Properties p;
  bool any_point = false;
  for (const PointCloud* part : parts) {
    const size_t n = part->size();
    check_optional_size("intensity", part->intensity.size(), n);
    check_optional_size("ring", part->ring.size(), n);
    check_optional_size("time_s", part->time_s.size(), n);
    if (n == 0) continue;
    any_point = true;
    p.intensity = p.intensity && part->has_intensity();
    p.ring = p.ring && part->has_ring();
    p.time = p.time && part->has_time();
  }
  return any_point ? p : Properties{false, false, false};
}

// Writes the parts' points one after the other; `point_fields` index the concatenation.
void write_parts(const std::filesystem::path& path, const std::vector<const PointCloud*>& parts,
                 const std::vector<ScalarField>& point_fields) {
  size_t n = 0;
  for (const PointCloud* part : parts) n += part->size();
  const Properties has = properties_of(parts);
  check_scalar_fields(point_fields, n, {"x", "y", "z", "intensity", "ring", "time"});

  std::vector<std::string> field_names;
  for (const auto& field : point_fields) field_names.push_back(field.name);
  const std::string header = ply_cloud_header(n, has.intensity, has.ring, has.time, field_names);

  const size_t point_bytes = 12 + (has.intensity ? 4 : 0) + (has.ring ? 2 : 0) +
                             (has.time ? 4 : 0) + 4 * point_fields.size();
  ReplacedFile file(path);
  file.append(header.data(), header.size());
  std::vector<char> chunk(kChunkPoints * point_bytes);
  char* at = chunk.data();
  size_t k = 0;  // index into the concatenation
  for (const PointCloud* part : parts) {
    for (size_t i = 0; i < part->size(); ++i, ++k) {
      for (int c = 0; c < 3; ++c) put(at, part->xyz[i][c]);
      if (has.intensity) put(at, part->intensity[i]);
      if (has.ring) put(at, part->ring[i]);
      if (has.time) put(at, part->time_s[i]);
      for (const auto& field : point_fields) put(at, field.values[k]);
      if (at == chunk.data() + chunk.size()) {
        file.append(chunk.data(), chunk.size());
        at = chunk.data();
      }
    }
  }
  file.append(chunk.data(), static_cast<size_t>(at - chunk.data()));
  file.commit();
}

}  // namespace

std::string ply_cloud_header(uint64_t points, bool intensity, bool ring, bool time,
                             const std::vector<std::string>& fields) {
  std::string header = "ply\nformat binary_little_endian 1.0\ncomment written by keel\n";
  header += "element vertex " + std::to_string(points) + "\n";
  header += "property float x\nproperty float y\nproperty float z\n";
  if (intensity) header += "property float intensity\n";
  if (ring) header += "property ushort ring\n";
  if (time) header += "property float time\n";
  for (const auto& field : fields) header += "property float " + field + "\n";
  return header + "end_header\n";
}

void write_ply_cloud(const std::filesystem::path& path, const PointCloud& cloud,
                     const std::vector<ScalarField>& point_fields) {
  write_parts(path, {&cloud}, point_fields);
}

void write_ply_cloud(const std::filesystem::path& path,
                     const std::vector<const PointCloud*>& parts) {
  write_parts(path, parts, {});
}

}  // namespace keel::io
