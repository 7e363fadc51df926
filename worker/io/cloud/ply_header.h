// The header of a PLY file (Turk's format, version 1.0): format, elements with their counts,
// and scalar or list properties with their types. One parser serves the point-cloud reader
// (ply_file.cc) and the mesh reader (mesh_ply_reader.cc); each checks on top of it what it
// needs of the elements (a point cloud starts with `vertex`, a mesh needs `face` lists).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace keel::io {

enum class PlyType { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };
enum class PlyFormat { kAscii, kBinaryLittleEndian, kBinaryBigEndian };

size_t ply_type_size(PlyType type);
bool ply_type_is_integer(PlyType type);
// "ascii", "binary_little_endian", "binary_big_endian".
const char* to_string(PlyFormat format);

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::kFloat32;  // item type for lists
  bool is_list = false;
  PlyType count_type = PlyType::kUint8;  // lists only; always an integer type
  size_t line = 0;                       // header line that declares it
};

struct PlyElement {
  std::string name;
  uint64_t count = 0;
  std::vector<PlyProperty> properties;
  size_t line = 0;  // header line that declares it
};

struct PlyHeader {
  PlyFormat format = PlyFormat::kAscii;
  std::string version;  // "1.0"
  size_t format_line = 0;
  std::vector<std::string> comments;  // text after `comment` and `obj_info`, in file order
  std::vector<PlyElement> elements;   // in file order, which is the order of the body
  size_t body_offset = 0;             // first byte after the end_header line
  size_t end_header_line = 0;         // the body (ascii) starts on the line after it
};

// Parses the header at the start of `bytes` (the whole file, or at least its header).
// Throws IoError "<file>:<line>: <what was expected>" for a missing 'ply' magic, a missing
// or unknown format or version, unknown keywords or types, negative or non-integer counts,
// a property before any element, a duplicate property name in an element, a non-integer
// list count type, or a header without end_header (truncated file).
PlyHeader parse_ply_header(std::string_view bytes, const std::string& file);

}  // namespace keel::io
