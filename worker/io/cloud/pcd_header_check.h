// What a PCD header must satisfy before Keel reads the body. A reader that trusts the header
// sums SIZE x COUNT in 32 bits, adds negative sizes, spends time in proportion to COUNT and
// allocates POINTS x the point size before reading a byte of the body (PCL's did: each of
// those was a crash or an out-of-memory found by fuzz_scan_file). The header (up to its DATA
// line) is checked against the PCD specification here, and its point count against the
// file's size.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "worker/io/cloud/packed_cloud.h"

namespace keel::io {

// Values per field (COUNT) read at most: PCL's own descriptors stop at a few hundred (VFH 308,
// SHOT 352, ESF 640).
constexpr uint64_t kMaxPcdFieldCount = 1 << 16;
// The bytes of a file read for its header: check_pcd_header() refuses a longer header.
constexpr size_t kPcdHeaderBytes = 1 << 16;

// `head` is the file's first kPcdHeaderBytes (or the whole file). The header is read as PCL
// reads it: to the first line that is not a header keyword, DATA included (PCL reads
// keywords after DATA too). Throws IoError naming `name` unless DATA is given once, FIELDS (or
// COLUMNS) once, SIZE, TYPE and COUNT at most once each with one value per field (sizes 1, 2, 4
// or 8; types I, U or F; counts 1..kMaxPcdFieldCount), WIDTH, HEIGHT and POINTS are unsigned
// 32-bit integers, and the points declared (the larger of POINTS and WIDTH x HEIGHT) fit in
// `file_size` bytes: at the point size the header gives for binary, 88 times that for
// binary_compressed (LZF's largest expansion), a byte a value for ascii. Keywords are matched
// as PCL matches them, by prefix.
void check_pcd_header(std::string_view head, uint64_t file_size, const std::string& name);

enum class PcdEncoding { kAscii, kBinary, kBinaryCompressed };

// What Keel's PCD reader needs of a checked header.
struct PcdLayout {
  std::vector<PackedField> fields;  // packed in order, padding fields ("_") included
  size_t point_step = 0;            // bytes of a point record
  size_t values_per_point = 0;      // the sum of COUNT (values in an ascii row)
  uint32_t width = 0, height = 1;
  uint64_t points = 0;  // WIDTH x HEIGHT
  PcdEncoding encoding = PcdEncoding::kBinary;
  size_t data_offset = 0;  // the body's first byte: the one after the DATA line
};

// check_pcd_header()'s checks, plus: DATA is exactly ascii, binary or binary_compressed;
// TYPE F has SIZE 4 or 8; WIDTH x HEIGHT equals POINTS when both are given (PCD v0.5: no
// WIDTH means WIDTH = POINTS, HEIGHT 1). Throws IoError naming `name`.
PcdLayout parse_pcd_header(std::string_view head, uint64_t file_size, const std::string& name);
// PCD's TYPE letter and SIZE as a field type; nothing for F of size 1 or 2, or another letter.
std::optional<FieldType> pcd_field_type(char type, uint64_t size);

}  // namespace keel::io
