// What a PCD header must satisfy before PCL reads it. PCL's readHeader trusts the header: it
// sums SIZE x COUNT in 32 bits, adds negative sizes, spends time in proportion to COUNT and
// allocates POINTS x the point size before reading a byte of the body. Each of those was a
// crash or an out-of-memory found by fuzz_scan_file. The header (up to its DATA line) is
// checked against the PCD specification here, and its point count against the file's size.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

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

}  // namespace keel::io
