#include "worker/io/mesh/mesh_parse_util.h"

#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

#include "worker/io/display_path.h"
#include "worker/io/mesh/mesh_reader.h"

namespace keel::io::mesh_detail {

void fail(const std::filesystem::path& path, size_t line, const std::string& what) {
  std::string message = display_path(path);
  if (line > 0) message += ":" + std::to_string(line);
  throw MeshReadError(message + ": " + what);
}

std::string read_file_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, 0, "cannot open file");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) fail(path, 0, "read error");
  return std::move(buffer).str();
}

bool LineCursor::next(std::string_view* line) {
  if (offset_ >= text_.size()) return false;
  size_t end = text_.find('\n', offset_);
  if (end == std::string_view::npos) end = text_.size();
  std::string_view result = text_.substr(offset_, end - offset_);
  if (!result.empty() && result.back() == '\r') result.remove_suffix(1);
  offset_ = end + 1;
  ++next_line_number_;
  *line = result;
  return true;
}

bool LineCursor::next_content(std::string_view* line, char comment) {
  while (next(line)) {
    const size_t first = line->find_first_not_of(" \t");
    if (first == std::string_view::npos) continue;
    if (comment != '\0' && (*line)[first] == comment) continue;
    return true;
  }
  return false;
}

void split_whitespace(std::string_view line, std::vector<std::string_view>* tokens) {
  tokens->clear();
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    const size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
    if (i > start) tokens->push_back(line.substr(start, i - start));
  }
}

bool parse_double(std::string_view token, double* value) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  const char* end = token.data() + token.size();
  const auto result = std::from_chars(token.data(), end, *value);
  return result.ec == std::errc() && result.ptr == end;
}

bool parse_int64(std::string_view token, int64_t* value) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  const char* end = token.data() + token.size();
  const auto result = std::from_chars(token.data(), end, *value);
  return result.ec == std::errc() && result.ptr == end;
}

bool is_finite(const Eigen::Vector3d& p) {
  return std::isfinite(p.x()) && std::isfinite(p.y()) && std::isfinite(p.z());
}

void add_polygon_fan(const std::vector<int>& polygon, std::vector<Eigen::Vector3i>* faces) {
  for (size_t i = 1; i + 1 < polygon.size(); ++i) {
    faces->emplace_back(polygon[0], polygon[i], polygon[i + 1]);
  }
}

void require_faces(const std::filesystem::path& path, const TriangleMesh& mesh) {
  if (mesh.faces.empty()) fail(path, 0, "mesh has no faces (expected at least one polygon)");
}

std::string quoted(std::string_view token) {
  constexpr size_t kMaxShown = 40;
  std::string shown(token.substr(0, kMaxShown));
  if (token.size() > kMaxShown) shown += "...";
  return "'" + shown + "'";
}

}  // namespace keel::io::mesh_detail
