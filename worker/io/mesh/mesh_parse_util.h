// Helpers the mesh readers share: whole-file reads, line and token cursors with line
// numbers, strict number parsing and errors that name the file and line.
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "core/triangle_mesh.h"

namespace keel::io::mesh_detail {

// Throws MeshReadError "<path>:<line>: <what>" (without ":<line>" when line == 0).
[[noreturn]] void fail(const std::filesystem::path& path, size_t line, const std::string& what);

// The whole file; throws MeshReadError naming the file when it cannot be read.
std::string read_file_bytes(const std::filesystem::path& path);

// Walks text line by line (LF or CRLF), counting lines from 1.
class LineCursor {
 public:
  explicit LineCursor(std::string_view text, size_t first_line_number = 1)
      : text_(text), next_line_number_(first_line_number) {}
  // The next line without its line ending; false at the end of the text.
  bool next(std::string_view* line);
  // Like next(), but skips lines that are blank or whose first token starts with `comment`
  // (pass '\0' for no comments).
  bool next_content(std::string_view* line, char comment);
  // Number of the line next() returned last.
  size_t line_number() const { return next_line_number_ - 1; }
  size_t offset() const { return offset_; }
  bool at_end() const { return offset_ >= text_.size(); }

 private:
  std::string_view text_;
  size_t offset_ = 0;
  size_t next_line_number_;
};

// Splits on spaces and tabs.
void split_whitespace(std::string_view line, std::vector<std::string_view>* tokens);

// Whole-token parses (a leading '+' is accepted); false for anything else. parse_double
// accepts "nan"/"inf" so callers can reject them with a precise message.
bool parse_double(std::string_view token, double* value);
bool parse_int64(std::string_view token, int64_t* value);

bool is_finite(const Eigen::Vector3d& p);

// Appends the fan (p0, p_i, p_i+1) of a polygon with at least three corners.
void add_polygon_fan(const std::vector<int>& polygon, std::vector<Eigen::Vector3i>* faces);

// Last checks every reader makes: at least one face.
void require_faces(const std::filesystem::path& path, const TriangleMesh& mesh);

std::string quoted(std::string_view token);

}  // namespace keel::io::mesh_detail
