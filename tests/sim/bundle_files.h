// Writers for the files of a mission bundle (docs/mission-format.md): binary PCD scans,
// binary PLY meshes, stream CSVs and TUM trajectories. Stamps go through format_seconds, so
// they are exact nanoseconds.
#pragma once

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "core/point_cloud.h"
#include "core/pose.h"
#include "core/triangle_mesh.h"

namespace keel::sim {

// Binary PCD v0.7 with the fields the cloud has: x y z [intensity] [ring (uint16)] [time].
void write_pcd_binary(const std::string& path, const PointCloud& cloud);

// Binary little-endian PLY, float vertices, int32 face indices.
void write_ply_binary(const std::string& path, const TriangleMesh& mesh);

// A buffered text file that throws on any write error, naming the file.
class TextFile {
 public:
  explicit TextFile(const std::string& path);
  ~TextFile();
  TextFile(const TextFile&) = delete;
  TextFile& operator=(const TextFile&) = delete;
  void line(const std::string& text);
  // Row "<stamp>,<v0>,<v1>,..." with values printed as %.9g ("nan" for NaN).
  void row(TimeNs t_ns, const double* values, size_t count);
  void close();

 private:
  std::string path_;
  std::FILE* file_ = nullptr;
};

// TUM lines "t x y z qx qy qz qw" for T_world_body.
void write_tum(const std::string& path, const Trajectory& trajectory);

}  // namespace keel::sim
