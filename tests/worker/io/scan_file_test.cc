#include "worker/io/cloud/scan_file.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>

#include "io_test_util.h"
#include "worker/io/scan_source.h"

namespace keel::io {
namespace {

using proto::PointTimeSpec;
using proto::TimeReference;
using proto::TimeUnit;
using testing::expect_error;
using testing::TempDir;
using testing::write_text;

constexpr TimeNs kStamp = 1700000000250000000LL;

// A sweep of n points: known positions, intensities, rings and times 0..0.1 s.
PointCloud make_sweep(size_t n) {
  PointCloud cloud;
  cloud.t_ns = kStamp;
  for (size_t i = 0; i < n; ++i) {
    cloud.xyz.emplace_back(0.5f * i, -0.25f * i, 1.0f + 0.001f * i);
    cloud.intensity.push_back(static_cast<float>(i % 256));
    cloud.ring.push_back(static_cast<uint16_t>(i % 16));
    cloud.time_s.push_back(static_cast<float>(0.1 * i / (n - 1)));
  }
  return cloud;
}

ScanReadOptions read_options(TimeUnit unit, TimeReference reference,
                             const std::string& field = "time") {
  ScanReadOptions o;
  o.point_time = PointTimeSpec{field, unit, reference};
  o.sweep_period_s = 0.1;
  return o;
}

void expect_same(const PointCloud& a, const PointCloud& b, double time_tolerance) {
  ASSERT_EQ(a.size(), b.size());
  ASSERT_EQ(b.intensity.size(), b.size());
  ASSERT_EQ(b.ring.size(), b.size());
  ASSERT_EQ(b.time_s.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a.xyz[i], b.xyz[i]) << i;
    EXPECT_EQ(a.intensity[i], b.intensity[i]);
    EXPECT_EQ(a.ring[i], b.ring[i]);
    EXPECT_NEAR(a.time_s[i], b.time_s[i], time_tolerance) << i;
  }
}

struct Case {
  const char* name;
  ScanEncoding encoding;
  FieldType time_type;
  TimeUnit unit;
  TimeReference reference;
  double tolerance;
};

TEST(ScanFile, RoundTripsEveryEncodingAndTimeConvention) {
  const Case cases[] = {
      {"a.pcd", ScanEncoding::kAscii, FieldType::kFloat32, TimeUnit::kSeconds,
       TimeReference::kScanStart, 1e-7},
      {"b.pcd", ScanEncoding::kBinary, FieldType::kFloat32, TimeUnit::kSeconds,
       TimeReference::kScanStart, 0},
      {"c.pcd", ScanEncoding::kBinaryCompressed, FieldType::kFloat32, TimeUnit::kSeconds,
       TimeReference::kScanStart, 0},
      {"d.pcd", ScanEncoding::kBinary, FieldType::kUint32, TimeUnit::kNanoseconds,
       TimeReference::kScanStart, 1e-9},
      {"e.pcd", ScanEncoding::kBinary, FieldType::kFloat64, TimeUnit::kSeconds,
       TimeReference::kAbsolute, 1e-6},
      {"f.pcd", ScanEncoding::kBinary, FieldType::kUint64, TimeUnit::kNanoseconds,
       TimeReference::kAbsolute, 1e-9},
      {"g.pcd", ScanEncoding::kAscii, FieldType::kFloat64, TimeUnit::kMicroseconds,
       TimeReference::kScanStart, 1e-9},
      {"h.ply", ScanEncoding::kAscii, FieldType::kFloat32, TimeUnit::kSeconds,
       TimeReference::kScanStart, 1e-7},
      {"i.ply", ScanEncoding::kBinary, FieldType::kFloat32, TimeUnit::kSeconds,
       TimeReference::kScanStart, 0},
      {"j.ply", ScanEncoding::kBinary, FieldType::kUint32, TimeUnit::kNanoseconds,
       TimeReference::kScanStart, 1e-9},
      {"k.ply", ScanEncoding::kBinary, FieldType::kFloat64, TimeUnit::kSeconds,
       TimeReference::kAbsolute, 1e-6},
  };
  TempDir dir;
  const PointCloud sweep = make_sweep(1000);
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const PointTimeSpec spec{"t", c.unit, c.reference};
    write_scan_file(dir / c.name, sweep, {c.encoding, PointTimeEncoding{spec, c.time_type}});
    const ScanFileInfo info = read_scan_info(dir / c.name);
    EXPECT_EQ(info.num_points, 1000u);
    ASSERT_EQ(info.fields.size(), 6u);
    EXPECT_EQ(info.fields[5].type, c.time_type);
    const PointCloud read =
        read_scan_file(dir / c.name, kStamp, read_options(c.unit, c.reference, "t"));
    EXPECT_EQ(read.t_ns, kStamp);
    expect_same(sweep, read, c.tolerance + 1e-9);
  }
}

TEST(ScanFile, HandWrittenOusterStylePcdNanoseconds) {
  TempDir dir;
  write_text(dir / "o.pcd",
             "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z t\nSIZE 4 4 4 4\nTYPE F F F U\nCOUNT 1 1 1 1\n"
             "WIDTH 4\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 4\nDATA ascii\n"
             "1 2 3 0\n4 5 6 50000000\nnan nan nan 60000000\n7 8 9 99999999\n");
  // The NaN point is dropped.
  const PointCloud c = read_scan_file(
      dir / "o.pcd", 0, read_options(TimeUnit::kNanoseconds, TimeReference::kScanStart, "t"));
  ASSERT_EQ(c.size(), 3u);
  EXPECT_EQ(c.xyz[1], Eigen::Vector3f(4, 5, 6));
  EXPECT_FLOAT_EQ(c.time_s[1], 0.05f);
  EXPECT_FLOAT_EQ(c.time_s[2], 0.099999999f);
  EXPECT_FALSE(c.has_intensity());
}

TEST(ScanFile, WrongDeclaredUnitIsNamedWithWhatWasFound) {
  TempDir dir;
  const PointCloud sweep = make_sweep(100);
  // Ouster-style uint32 ns, declared as seconds: offsets up to 1e8 s.
  write_scan_file(dir / "ns.pcd", sweep,
                  {ScanEncoding::kBinary,
                   PointTimeEncoding{{"t", TimeUnit::kNanoseconds, TimeReference::kScanStart},
                                     FieldType::kUint32}});
  expect_error(
      [&] {
        read_scan_file(dir / "ns.pcd", kStamp,
                       read_options(TimeUnit::kSeconds, TimeReference::kScanStart, "t"));
      },
      {"ns.pcd", "field 't'", "declared unit s", "1e+08", "beyond 10 sweep periods",
       "fit unit ns"});
  // Velodyne-style float seconds, declared as ns: a 0.1 s sweep would span 0.1 ns.
  write_scan_file(dir / "s.pcd", sweep,
                  {ScanEncoding::kBinary,
                   PointTimeEncoding{{"t", TimeUnit::kSeconds, TimeReference::kScanStart},
                                     FieldType::kFloat32}});
  expect_error(
      [&] {
        read_scan_file(dir / "s.pcd", kStamp,
                       read_options(TimeUnit::kNanoseconds, TimeReference::kScanStart, "t"));
      },
      {"s.pcd", "field 't'", "declared unit ns", "fit unit s"});
  // Offsets declared absolute.
  expect_error(
      [&] {
        read_scan_file(dir / "s.pcd", kStamp,
                       read_options(TimeUnit::kSeconds, TimeReference::kAbsolute, "t"));
      },
      {"s.pcd", "reference absolute", "reference scan_start?"});
  // Absolute stamps declared as offsets.
  write_scan_file(
      dir / "abs.pcd", sweep,
      {ScanEncoding::kBinary, PointTimeEncoding{{"t", TimeUnit::kSeconds, TimeReference::kAbsolute},
                                                FieldType::kFloat64}});
  expect_error(
      [&] {
        read_scan_file(dir / "abs.pcd", kStamp,
                       read_options(TimeUnit::kSeconds, TimeReference::kScanStart, "t"));
      },
      {"abs.pcd", "reference absolute?"});
  // A missing time field names the fields present.
  expect_error(
      [&] {
        read_scan_file(dir / "abs.pcd", kStamp,
                       read_options(TimeUnit::kSeconds, TimeReference::kScanStart, "time"));
      },
      {"abs.pcd", "no per-point time field 'time'", "x y z intensity ring t"});
}

void truncate_file(const std::filesystem::path& path, size_t remove_bytes) {
  std::filesystem::resize_file(path, std::filesystem::file_size(path) - remove_bytes);
}

TEST(ScanFile, TruncatedPcdIsNamed) {
  TempDir dir;
  const PointCloud sweep = make_sweep(500);
  const ScanWriteOptions binary{ScanEncoding::kBinary, std::nullopt};
  write_scan_file(dir / "b.pcd", sweep, binary);
  // PCL pads binary files to a page; cut into the points themselves.
  truncate_file(dir / "b.pcd", std::filesystem::file_size(dir / "b.pcd") / 2);
  expect_error([&] { read_scan_file(dir / "b.pcd", 0); }, {"b.pcd", "truncated PCD", "500 points"});
  write_scan_file(dir / "c.pcd", sweep, {ScanEncoding::kBinaryCompressed, std::nullopt});
  truncate_file(dir / "c.pcd", std::filesystem::file_size(dir / "c.pcd") / 2);
  expect_error([&] { read_scan_file(dir / "c.pcd", 0); }, {"c.pcd", "truncated PCD"});
  write_scan_file(dir / "a.pcd", sweep, {ScanEncoding::kAscii, std::nullopt});
  truncate_file(dir / "a.pcd", 2000);
  expect_error([&] { read_scan_file(dir / "a.pcd", 0); }, {"a.pcd"});
  write_text(dir / "h.pcd", "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\n");
  expect_error([&] { read_scan_file(dir / "h.pcd", 0); }, {"h.pcd", "PCD header", "no DATA line"});
  // A keyword alone on its line (found by fuzz_scan_file): PCL threw std::out_of_range.
  write_text(dir / "k.pcd",
             "VERSION 0.7\nFIELDS x\nSIZE 4\nTYPE F\nCOUNT 1\nWIDTH 1\nHEIGHT 1\nPOINTS 1\n"
             "DATA\nDATA binary\n0000");
  expect_error([&] { read_scan_info(dir / "k.pcd"); }, {"k.pcd", "malformed PCD header"});
  expect_error([&] { read_scan_file(dir / "k.pcd", 0); }, {"k.pcd", "malformed PCD header"});
  // No FIELDS line: PCL read the body through a null pointer (SEGV, fuzz_scan_file).
  write_text(dir / "f.pcd", "VERSION 0.7\nDATA binary\n0123");
  expect_error([&] { read_scan_file(dir / "f.pcd", 0); }, {"f.pcd", "no FIELDS"});
  // A COUNT past 32 bits: PCL's 32-bit point size wrapped and its ascii reader asked for
  // 128 GiB (fuzz_scan_file, regressions/scan_file/pcd-count-overflow).
  write_text(dir / "n.pcd",
             "VERSION 0.7\nFIELDS x y\nSIZE 4 4\nTYPE F F\nCOUNT 4294967295 1\nWIDTH 1\n"
             "HEIGHT 1\nPOINTS 1\nDATA ascii\n1 2\n");
  expect_error([&] { read_scan_info(dir / "n.pcd"); }, {"n.pcd", "malformed PCD header", "COUNT"});
  expect_error([&] { read_scan_file(dir / "n.pcd", 0); }, {"n.pcd", "COUNT"});
  // A binary_compressed body claiming more than LZF can unpack from its bytes.
  write_text(dir / "z.pcd",
             "VERSION 0.7\nFIELDS x\nSIZE 4\nTYPE F\nCOUNT 1\nWIDTH 100000000\nHEIGHT 1\n"
             "POINTS 100000000\nDATA binary_compressed\n" +
                 std::string("\x10\x00\x00\x00\x00\x84\xd7\x17", 8) + std::string(16, 'a'));
  expect_error([&] { read_scan_file(dir / "z.pcd", 0); }, {"z.pcd", "expands at most 88 times"});
  // A ring outside 0..65535 (a float ring of -12208.1 was undefined behaviour, UBSan,
  // fuzz_scan_file): named with its point.
  write_text(dir / "r.pcd",
             "VERSION 0.7\nFIELDS x y z ring\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\n"
             "WIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n1 2 3 4\n1 2 3 -3.5\n");
  expect_error([&] { read_scan_file(dir / "r.pcd", 0); }, {"r.pcd", "point 1", "ring -3.5"});
  // A negative SIZE: PCL put the next field at byte 2^32 - 4 of a point and read there (a SEGV,
  // fuzz_scan_file). Without TYPE and COUNT lines PCL takes floats; the sizes here add up to
  // the point's 16 bytes all the same.
  write_text(dir / "s.pcd",
             "VERSION 0.7\nFIELDS x y z i\nSIZE -4 8 4 8\nWIDTH 1\nHEIGHT 1\nPOINTS 1\n"
             "DATA binary\n" +
                 std::string(16, '\0'));
  expect_error([&] { read_scan_file(dir / "s.pcd", 0); },
               {"s.pcd", "malformed PCD header", "SIZE of field 'x' is '-4'"});
}

TEST(ScanFile, TruncatedPlyIsNamed) {
  TempDir dir;
  const PointCloud sweep = make_sweep(500);
  write_scan_file(dir / "b.ply", sweep, {ScanEncoding::kBinary, std::nullopt});
  truncate_file(dir / "b.ply", 10);
  expect_error([&] { read_scan_file(dir / "b.ply", 0); },
               {"b.ply", "truncated PLY", "500 vertices"});
  write_scan_file(dir / "a.ply", sweep, {ScanEncoding::kAscii, std::nullopt});
  truncate_file(dir / "a.ply", 200);
  expect_error([&] { read_scan_file(dir / "a.ply", 0); }, {"a.ply:"});
  write_text(dir / "h.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n");
  expect_error([&] { read_scan_file(dir / "h.ply", 0); }, {"h.ply", "no end_header"});
  write_text(dir / "big.ply", "ply\nformat binary_big_endian 1.0\nelement vertex 1\nend_header\n");
  expect_error([&] { read_scan_file(dir / "big.ply", 0); }, {"big.ply:2:", "binary_big_endian"});
  write_text(dir / "x.ply",
             "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float "
             "y\nproperty float z\nend_header\n1 2 oops\n");
  expect_error([&] { read_scan_file(dir / "x.ply", 0); }, {"x.ply:8:", "property 'z'", "oops"});
}

std::string pcd_header(const std::string& fields, const std::string& counts, size_t points) {
  std::string size, type;
  for (size_t i = 0; i < counts.size(); i += 2) size += "4 ", type += "F ";
  return "# .PCD v0.7\nVERSION 0.7\nFIELDS " + fields + "\nSIZE " + size + "\nTYPE " + type +
         "\nCOUNT " + counts + "\nWIDTH " + std::to_string(points) +
         "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + std::to_string(points) +
         "\nDATA ascii\n";  // 11 lines: the first data row is line 12
}

TEST(ScanFile, MalformedAsciiPcdRowsAreNamed) {
  TempDir dir;
  const std::string xyzt = pcd_header("x y z t", "1 1 1 1", 2);
  // A valid file (a blank line in the body holds no point) reads exactly.
  write_text(dir / "ok.pcd", xyzt + "5 5 5 0.1\n\n6 7 8 0.2\n");
  const PointCloud ok = read_scan_file(dir / "ok.pcd", 0);
  ASSERT_EQ(ok.size(), 2u);
  EXPECT_EQ(ok.xyz[0], Eigen::Vector3f(5, 5, 5));
  EXPECT_EQ(ok.xyz[1], Eigen::Vector3f(6, 7, 8));
  // PCL would read the short row as a point at the origin.
  write_text(dir / "short.pcd", xyzt + "5 5 5 0.1\n6 6 6\n");
  expect_error([&] { read_scan_file(dir / "short.pcd", 0); },
               {"short.pcd:13:", "data row 2", "expected 4 values", "found 3"});
  write_text(dir / "long.pcd", xyzt + "5 5 5 0.1 9\n6 6 6 0.2\n");
  expect_error([&] { read_scan_file(dir / "long.pcd", 0); },
               {"long.pcd:12:", "data row 1", "expected 4 values", "found 5"});
  write_text(dir / "word.pcd", xyzt + "5 5 5 0.1\n6 six 6 0.2\n");
  expect_error([&] { read_scan_file(dir / "word.pcd", 0); },
               {"word.pcd:13:", "expected a number", "'six'"});
  write_text(dir / "more.pcd", xyzt + "5 5 5 0.1\n6 6 6 0.2\n7 7 7 0.3\n8 8 8 0.4\n");
  expect_error([&] { read_scan_file(dir / "more.pcd", 0); },
               {"more.pcd:14:", "2 data rows beyond", "POINTS 2"});
  write_text(dir / "fewer.pcd", xyzt + "5 5 5 0.1\n");
  expect_error([&] { read_scan_file(dir / "fewer.pcd", 0); },
               {"fewer.pcd", "truncated PCD", "POINTS declares 2", "has 1 rows"});
  // A row holds the sum of COUNT over FIELDS values: 1 + 1 + 1 + 3 here.
  const std::string counted = pcd_header("x y z n", "1 1 1 3", 1);
  write_text(dir / "count.pcd", counted + "1 2 3 0 0 1\n");
  const PointCloud c = read_scan_file(dir / "count.pcd", 0);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c.xyz[0], Eigen::Vector3f(1, 2, 3));
  write_text(dir / "count4.pcd", counted + "1 2 3 0\n");
  expect_error([&] { read_scan_file(dir / "count4.pcd", 0); },
               {"count4.pcd:12:", "expected 6 values", "found 4"});
}

const std::string kPlyXyz = "property float x\nproperty float y\nproperty float z\n";

TEST(ScanFile, PlyDataBeyondTheHeaderIsNamed) {
  TempDir dir;
  const std::string one = "ply\nformat ascii 1.0\nelement vertex 1\n" + kPlyXyz + "end_header\n";
  write_text(dir / "ok.ply", one + "1 2 3\n\n");  // trailing blank lines are not data
  const PointCloud ok = read_scan_file(dir / "ok.ply", 0);
  ASSERT_EQ(ok.size(), 1u);
  EXPECT_EQ(ok.xyz[0], Eigen::Vector3f(1, 2, 3));
  write_text(dir / "more.ply", one + "1 2 3\n4 5 6\n7 8 9\n");
  expect_error([&] { read_scan_file(dir / "more.ply", 0); },
               {"more.ply:9:", "2 data lines left over", "element vertex 1"});
  write_text(dir / "long.ply", one + "1 2 3 4\n");
  expect_error([&] { read_scan_file(dir / "long.ply", 0); },
               {"long.ply:8:", "expected 3 vertex values, found 4"});
  // Elements after the vertices are skipped, and counted.
  const std::string faces = "ply\nformat ascii 1.0\nelement vertex 3\n" + kPlyXyz +
                            "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                            "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  write_text(dir / "faces.ply", faces);
  const PointCloud f = read_scan_file(dir / "faces.ply", 0);
  ASSERT_EQ(f.size(), 3u);
  EXPECT_EQ(f.xyz[2], Eigen::Vector3f(0, 1, 0));
  write_text(dir / "faces_more.ply", faces + "3 2 1 0\n");
  expect_error(
      [&] { read_scan_file(dir / "faces_more.ply", 0); },
      {"faces_more.ply:14:", "1 data lines left over", "element vertex 3, element face 1"});
  write_text(dir / "count.ply", "ply\nformat ascii 1.0\nelement vertex 1\n" + kPlyXyz +
                                    "element face x\nend_header\n");
  expect_error([&] { read_scan_file(dir / "count.ply", 0); },
               {"count.ply:7:", "bad count of element 'face'"});

  // Binary: trailing bytes after the declared vertices.
  const PointCloud sweep = make_sweep(500);
  write_scan_file(dir / "b.ply", sweep, {ScanEncoding::kBinary, std::nullopt});
  const PointCloud b = read_scan_file(dir / "b.ply", 0);
  ASSERT_EQ(b.size(), 500u);
  EXPECT_EQ(b.xyz[499], sweep.xyz[499]);
  std::ofstream(dir / "b.ply", std::ios::binary | std::ios::app) << "12345";
  expect_error([&] { read_scan_file(dir / "b.ply", 0); },
               {"b.ply", "5 bytes left over", "element vertex 500"});
  // Binary with a face list after the vertices: the list lengths are read from the data.
  std::string bin = "ply\nformat binary_little_endian 1.0\nelement vertex 3\n" + kPlyXyz +
                    "element face 2\nproperty list uchar int vertex_indices\nend_header\n";
  const float xyz[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  bin.append(reinterpret_cast<const char*>(xyz), sizeof(xyz));
  const int32_t triangle[3] = {0, 1, 2};
  const int32_t quad[4] = {0, 1, 2, 0};
  bin += '\3';
  bin.append(reinterpret_cast<const char*>(triangle), sizeof(triangle));
  bin += '\4';
  bin.append(reinterpret_cast<const char*>(quad), sizeof(quad));
  write_text(dir / "bf.ply", bin);
  const PointCloud bf = read_scan_file(dir / "bf.ply", 0);
  ASSERT_EQ(bf.size(), 3u);
  EXPECT_EQ(bf.xyz[1], Eigen::Vector3f(1, 0, 0));
  write_text(dir / "bf_more.ply", bin + "x");
  expect_error([&] { read_scan_file(dir / "bf_more.ply", 0); },
               {"bf_more.ply", "1 bytes left over", "element vertex 3, element face 2"});
  write_text(dir / "bf_short.ply", bin.substr(0, bin.size() - 4));
  expect_error([&] { read_scan_file(dir / "bf_short.ply", 0); },
               {"bf_short.ply", "truncated PLY", "element 'face' item 1 of 2"});
}

// An ascii PLY value its property's type cannot hold is refused naming the file, line and
// property (converting it was undefined behaviour: fuzz_scan_file, 'nan' for a uchar).
TEST(ScanFile, AsciiPlyValueOutsideItsTypeIsRefused) {
  TempDir dir;
  const std::string header =
      "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
      "property float z\nproperty uchar ring\nend_header\n";
  write_text(dir / "a.ply", header + "0 0 0 1\n1 1 1 nan\n");
  expect_error([&] { (void)read_scan_file(dir / "a.ply", 0); },
               {"a.ply:10", "property 'ring'", "'nan' is not a"});
  write_text(dir / "b.ply", header + "0 0 0 256\n");
  expect_error([&] { (void)read_scan_file(dir / "b.ply", 0); }, {"b.ply:9", "'256' is not a"});
  write_text(dir / "c.ply", header + "1e300 0 0 1\n");
  expect_error([&] { (void)read_scan_file(dir / "c.ply", 0); },
               {"c.ply:9", "property 'x'", "'1e300' is not a"});
  write_text(dir / "d.ply", header + "0.5 -2 nan 255\n0 0 0 0\n");  // NaN stays NaN in a float
  EXPECT_NO_THROW((void)read_scan_file(dir / "d.ply", 0, ScanReadOptions{{}, 0.0, true, ""}));
  // The last vertex line without its newline (fuzz_scan_file: std::out_of_range, not an IoError).
  write_text(dir / "e.ply", header + "0 0 0 1\n1 2 3 4");
  EXPECT_EQ(read_scan_file(dir / "e.ply", 0).size(), 2u);
}

TEST(ScanFile, ScanFolderReaderStreamsInIndexOrder) {
  TempDir dir;
  std::vector<IndexEntry> index;
  for (int k = 0; k < 4; ++k) {
    PointCloud c = make_sweep(10 + k);
    c.t_ns = kStamp + k * 100000000LL;
    const auto path = dir / ("s" + std::to_string(k) + (k % 2 ? ".ply" : ".pcd"));
    write_scan_file(path, c,
                    {ScanEncoding::kBinary,
                     PointTimeEncoding{{"time", TimeUnit::kSeconds, TimeReference::kScanStart},
                                       FieldType::kFloat32}});
    index.push_back({c.t_ns, path, 0});
  }
  write_folder_index(dir.path(), index);
  ScanFolderReader reader(dir.path(), read_options(TimeUnit::kSeconds, TimeReference::kScanStart));
  ASSERT_EQ(reader.size(), 4u);
  PointCloud c;
  for (int k = 0; k < 4; ++k) {
    ASSERT_TRUE(reader.next(c));
    EXPECT_EQ(c.size(), 10u + k);
    EXPECT_EQ(c.t_ns, kStamp + k * 100000000LL);
  }
  EXPECT_FALSE(reader.next(c));
  write_text(dir / "index.csv", "t,file\n1.0,s0.pcd\n1.0,s1.ply\n");
  expect_error([&] { ScanFolderReader(dir.path(), {}); }, {"index.csv:3:", "duplicate timestamp"});
  write_text(dir / "index.csv", "t,file\n1.0,s0.pcd\n2.0,gone.pcd\n");
  expect_error([&] { ScanFolderReader(dir.path(), {}); }, {"index.csv:3:", "'gone.pcd' not found"});
}

std::filesystem::path shared(const char* name) {
  return std::filesystem::path(KEEL_SHARED_DIR) / "data" / name;
}

TEST(ScanFile, RealVelodyneSweep) {
  if (!std::filesystem::exists(shared("test_scan_vlp16.pcd")))
    GTEST_SKIP() << "shared/data/test_scan_vlp16.pcd absent";
  const ScanFileInfo info = read_scan_info(shared("test_scan_vlp16.pcd"));
  EXPECT_EQ(info.num_points, 25760u);
  EXPECT_EQ(info.format, "pcd ascii");
  const PointCloud c = read_scan_file(shared("test_scan_vlp16.pcd"), kStamp,
                                      read_options(TimeUnit::kSeconds, TimeReference::kScanStart));
  EXPECT_EQ(c.size(), 25760u);
  ASSERT_TRUE(c.has_time());
  ASSERT_TRUE(c.has_ring());
  // This file's `time` column holds 0 for every point (checked with awk), so its span is 0
  // and the ~0.1 s of a 10 Hz sweep cannot be checked from it; the offsets must still read as
  // valid (finite, within the sweep).
  const auto [lo, hi] = std::minmax_element(c.time_s.begin(), c.time_s.end());
  EXPECT_EQ(*lo, 0.0f);
  EXPECT_EQ(*hi, 0.0f);
  EXPECT_LE(*std::max_element(c.ring.begin(), c.ring.end()), 15);
  // One full sweep: the azimuths of the points cover the circle (every 10 degree bin hit).
  std::vector<bool> bins(36, false);
  for (const auto& p : c.xyz) {
    const double azimuth = std::atan2(p.y(), p.x()) + M_PI;
    bins[std::min(35, static_cast<int>(azimuth / (2 * M_PI) * 36))] = true;
  }
  EXPECT_EQ(std::count(bins.begin(), bins.end(), true), 36);
}

TEST(ScanFile, StanfordBunny) {
  if (!std::filesystem::exists(shared("bun0.pcd"))) GTEST_SKIP() << "shared/data/bun0.pcd absent";
  const PointCloud c = read_scan_file(shared("bun0.pcd"), 0);
  EXPECT_EQ(c.size(), 397u);
  EXPECT_FALSE(c.has_time());
  EXPECT_NEAR(c.xyz[0].x(), 0.0054215998f, 1e-9);
  expect_error(
      [&] {
        read_scan_file(shared("bun0.pcd"), 0,
                       read_options(TimeUnit::kSeconds, TimeReference::kScanStart));
      },
      {"bun0.pcd", "no per-point time field 'time'", "normal_x"});
}

}  // namespace
}  // namespace keel::io
