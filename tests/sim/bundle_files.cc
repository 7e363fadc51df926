#include "tests/sim/bundle_files.h"

#include <cmath>
#include <cstring>
#include <stdexcept>

#include "core/time.h"

namespace keel::sim {
namespace {

std::FILE* open_or_throw(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) throw std::runtime_error("cannot write " + path + ": " + std::strerror(errno));
  return f;
}

void write_or_throw(std::FILE* f, const void* data, size_t size, const std::string& path) {
  if (size > 0 && std::fwrite(data, 1, size, f) != size)
    throw std::runtime_error("write failed: " + path);
}

void close_or_throw(std::FILE* f, const std::string& path) {
  if (std::fclose(f) != 0) throw std::runtime_error("close failed: " + path);
}

}  // namespace

void write_pcd_binary(const std::string& path, const PointCloud& cloud) {
  const size_t n = cloud.size();
  const bool has_i = cloud.has_intensity(), has_r = cloud.has_ring(), has_t = cloud.has_time();
  std::string fields = "x y z", sizes = "4 4 4", types = "F F F", counts = "1 1 1";
  size_t stride = 12;
  if (has_i) fields += " intensity", sizes += " 4", types += " F", counts += " 1", stride += 4;
  if (has_r) fields += " ring", sizes += " 2", types += " U", counts += " 1", stride += 2;
  if (has_t) fields += " time", sizes += " 4", types += " F", counts += " 1", stride += 4;
  std::string header = "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS " + fields +
                       "\nSIZE " + sizes + "\nTYPE " + types + "\nCOUNT " + counts + "\nWIDTH " +
                       std::to_string(n) + "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " +
                       std::to_string(n) + "\nDATA binary\n";
  std::vector<char> body(n * stride);
  char* out = body.data();
  for (size_t i = 0; i < n; ++i) {
    std::memcpy(out, cloud.xyz[i].data(), 12), out += 12;
    if (has_i) std::memcpy(out, &cloud.intensity[i], 4), out += 4;
    if (has_r) std::memcpy(out, &cloud.ring[i], 2), out += 2;
    if (has_t) std::memcpy(out, &cloud.time_s[i], 4), out += 4;
  }
  std::FILE* f = open_or_throw(path);
  write_or_throw(f, header.data(), header.size(), path);
  write_or_throw(f, body.data(), body.size(), path);
  close_or_throw(f, path);
}

void write_ply_binary(const std::string& path, const TriangleMesh& mesh) {
  const std::string header =
      "ply\nformat binary_little_endian 1.0\ncomment keel-sim CAD model\nelement vertex " +
      std::to_string(mesh.num_vertices()) +
      "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
      std::to_string(mesh.num_faces()) + "\nproperty list uchar int vertex_indices\nend_header\n";
  std::vector<char> body;
  body.reserve(mesh.num_vertices() * 12 + mesh.num_faces() * 13);
  for (const auto& v : mesh.vertices) {
    const float xyz[3] = {float(v.x()), float(v.y()), float(v.z())};
    body.insert(body.end(), reinterpret_cast<const char*>(xyz),
                reinterpret_cast<const char*>(xyz) + 12);
  }
  for (const auto& f : mesh.faces) {
    body.push_back(3);
    const int32_t idx[3] = {f[0], f[1], f[2]};
    body.insert(body.end(), reinterpret_cast<const char*>(idx),
                reinterpret_cast<const char*>(idx) + 12);
  }
  std::FILE* f = open_or_throw(path);
  write_or_throw(f, header.data(), header.size(), path);
  write_or_throw(f, body.data(), body.size(), path);
  close_or_throw(f, path);
}

TextFile::TextFile(const std::string& path) : path_(path), file_(open_or_throw(path)) {}

TextFile::~TextFile() {
  if (file_) std::fclose(file_);
}

void TextFile::line(const std::string& text) {
  write_or_throw(file_, text.data(), text.size(), path_);
  write_or_throw(file_, "\n", 1, path_);
}

void TextFile::row(TimeNs t_ns, const double* values, size_t count) {
  std::string text = format_seconds(t_ns);
  char buffer[40];
  for (size_t i = 0; i < count; ++i) {
    if (std::isnan(values[i])) {
      text += ",nan";
      continue;
    }
    std::snprintf(buffer, sizeof(buffer), ",%.9g", values[i]);
    text += buffer;
  }
  line(text);
}

void TextFile::close() {
  if (!file_) return;
  std::FILE* f = file_;
  file_ = nullptr;
  close_or_throw(f, path_);
}

void write_tum(const std::string& path, const Trajectory& trajectory) {
  TextFile file(path);
  char buffer[256];
  for (const auto& p : trajectory) {
    const Eigen::Quaterniond q(p.T_world_body.linear());
    const Eigen::Vector3d t = p.T_world_body.translation();
    std::snprintf(buffer, sizeof(buffer), " %.9f %.9f %.9f %.9f %.9f %.9f %.9f", t.x(), t.y(),
                  t.z(), q.x(), q.y(), q.z(), q.w());
    file.line(format_seconds(p.t_ns) + buffer);
  }
  file.close();
}

}  // namespace keel::sim
