#include "worker/io/mesh/mesh_reader.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <limits>
#include <sstream>

#include "tests/worker/io/mesh_test_util.h"

namespace keel::io {
namespace {

using keel::testing::append_binary;
using keel::testing::canonical_triangles;
using keel::testing::error_of;
using keel::testing::scratch_dir;
using keel::testing::write_file;

// A box with distinct, float-exact coordinates on every axis (catches swapped axes), as six
// quads counter-clockwise seen from outside. Vertex i has bit 0 -> x, bit 1 -> y, bit 2 -> z.
const Eigen::Vector3d kLo(-1.0, 0.5, 2.0);
const Eigen::Vector3d kHi(3.0, 1.25, 4.5);
const int kQuads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                          {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};

Eigen::Vector3d cube_vertex(int i) {
  return {i & 1 ? kHi.x() : kLo.x(), i & 2 ? kHi.y() : kLo.y(), i & 4 ? kHi.z() : kLo.z()};
}

// The mesh every cube file must read as: 8 vertices, quads split as fans (q0 q1 q2), (q0 q2 q3).
TriangleMesh expected_cube() {
  TriangleMesh mesh;
  for (int i = 0; i < 8; ++i) mesh.vertices.push_back(cube_vertex(i));
  for (const auto& q : kQuads) {
    mesh.faces.emplace_back(q[0], q[1], q[2]);
    mesh.faces.emplace_back(q[0], q[2], q[3]);
  }
  return mesh;
}

void expect_same_indexed_mesh(const TriangleMesh& actual, const TriangleMesh& expected) {
  ASSERT_EQ(actual.vertices.size(), expected.vertices.size());
  ASSERT_EQ(actual.faces.size(), expected.faces.size());
  for (size_t i = 0; i < expected.vertices.size(); ++i) {
    EXPECT_EQ(actual.vertices[i], expected.vertices[i]) << "vertex " << i;
  }
  for (size_t f = 0; f < expected.faces.size(); ++f) {
    EXPECT_EQ(actual.faces[f], expected.faces[f]) << "face " << f;
  }
}

// --- writers of test files (independent of Keel's writers) ---------------------------------

std::string ply_ascii_cube(bool with_extras) {
  std::ostringstream out;
  out << "ply\nformat ascii 1.0\ncomment made by the test\n";
  out << "element vertex 8\nproperty float x\nproperty float y\nproperty float z\n";
  if (with_extras) {
    out << "property uchar red\nproperty uchar green\nproperty uchar blue\n"
           "property float confidence\n";
  }
  out << "element face 6\nproperty list uchar int vertex_indices\n";
  if (with_extras) out << "element edge 1\nproperty int vertex1\nproperty int vertex2\n";
  out << "end_header\n";
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d v = cube_vertex(i);
    out << v.x() << " " << v.y() << " " << v.z();
    if (with_extras) out << " " << 10 * i << " " << 20 * i << " " << 30 * i << " 0.5";
    out << "\n";
  }
  for (const auto& q : kQuads)
    out << "4 " << q[0] << " " << q[1] << " " << q[2] << " " << q[3] << "\n";
  if (with_extras) out << "0 7\n";
  return out.str();
}

// Doubles for positions, float normals, uint indices, a scalar after the face list and an
// extra element with a list, so the reader has to skip properly in binary.
std::string ply_binary_cube(bool big_endian) {
  std::string bytes = "ply\nformat ";
  bytes += big_endian ? "binary_big_endian" : "binary_little_endian";
  bytes +=
      " 1.0\nelement vertex 8\nproperty double x\nproperty double y\nproperty double z\n"
      "property float nx\nproperty float ny\nproperty float nz\n"
      "element face 6\nproperty list uchar uint vertex_indices\nproperty uchar flags\n"
      "element material 2\nproperty list ushort short samples\n"
      "end_header\n";
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d v = cube_vertex(i);
    for (int c = 0; c < 3; ++c) append_binary(&bytes, v[c], big_endian);
    const Eigen::Vector3f n = (v - 0.5 * (kLo + kHi)).normalized().cast<float>();
    for (int c = 0; c < 3; ++c) append_binary(&bytes, n[c], big_endian);
  }
  for (const auto& q : kQuads) {
    append_binary(&bytes, uint8_t{4}, big_endian);
    for (int c = 0; c < 4; ++c) append_binary(&bytes, static_cast<uint32_t>(q[c]), big_endian);
    append_binary(&bytes, uint8_t{7}, big_endian);
  }
  for (int m = 0; m < 2; ++m) {
    append_binary(&bytes, uint16_t{3}, big_endian);
    for (int s = 0; s < 3; ++s) append_binary(&bytes, static_cast<int16_t>(-s), big_endian);
  }
  return bytes;
}

// Every OBJ corner form: v, v/vt, v/vt/vn, v//vn, and negative (relative) indices.
std::string obj_cube() {
  std::ostringstream out;
  out << "# cube\nmtllib cube.mtl\no cube\n";
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d v = cube_vertex(i);
    out << "v " << v.x() << " " << v.y() << " " << v.z() << "\n";
  }
  out << "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n";
  out << "vn 0 0 -1\nvn 0 0 1\n";
  out << "g sides\nusemtl steel\ns off\n";
  const char* forms[6] = {"v", "v/vt", "v/vt/vn", "v//vn", "neg", "neg/vt/vn"};
  for (int f = 0; f < 6; ++f) {
    const std::string form = forms[f];
    out << "f";
    for (int c = 0; c < 4; ++c) {
      const int v = kQuads[f][c];
      const int index = form.rfind("neg", 0) == 0 ? v - 8 : v + 1;  // -8 is the first vertex
      out << " " << index;
      if (form == "v/vt" || form == "v/vt/vn" || form == "neg/vt/vn") out << "/" << c + 1;
      if (form == "v/vt/vn" || form == "neg/vt/vn") out << "/" << 1 + (f % 2);
      if (form == "v//vn") out << "//2";
    }
    out << "\n";
  }
  out << "l 1 2\n";
  return out.str();
}

std::vector<std::array<Eigen::Vector3d, 3>> cube_triangles() {
  std::vector<std::array<Eigen::Vector3d, 3>> triangles;
  const TriangleMesh cube = expected_cube();
  for (const auto& f : cube.faces) {
    triangles.push_back({cube.vertices[f[0]], cube.vertices[f[1]], cube.vertices[f[2]]});
  }
  return triangles;
}

std::string stl_ascii_cube() {
  std::ostringstream out;
  out << "solid cube\n";
  for (const auto& t : cube_triangles()) {
    const Eigen::Vector3d n = (t[1] - t[0]).cross(t[2] - t[0]).normalized();
    out << "  facet normal " << n.x() << " " << n.y() << " " << n.z() << "\n    outer loop\n";
    for (const auto& p : t) out << "      vertex " << p.x() << " " << p.y() << " " << p.z() << "\n";
    out << "    endloop\n  endfacet\n";
  }
  out << "endsolid cube\n";
  return out.str();
}

// Binary, but with a header that starts with "solid" as many CAD exporters write it.
std::string stl_binary_cube(const std::string& header_text = "solid cube exported by a CAD tool") {
  std::string bytes = header_text;
  bytes.resize(80, ' ');
  const auto triangles = cube_triangles();
  append_binary(&bytes, static_cast<uint32_t>(triangles.size()));
  for (const auto& t : triangles) {
    const Eigen::Vector3f n = (t[1] - t[0]).cross(t[2] - t[0]).normalized().cast<float>();
    for (int c = 0; c < 3; ++c) append_binary(&bytes, n[c]);
    for (const auto& p : t) {
      for (int c = 0; c < 3; ++c) append_binary(&bytes, static_cast<float>(p[c]));
    }
    append_binary(&bytes, uint16_t{0});
  }
  return bytes;
}

std::string off_cube(bool counts_on_header_line) {
  std::ostringstream out;
  out << (counts_on_header_line ? "OFF 8 6 12\n" : "OFF\n# a comment\n8 6 12\n");
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d v = cube_vertex(i);
    out << v.x() << " " << v.y() << " " << v.z() << "\n";
  }
  for (const auto& q : kQuads) {
    out << "4 " << q[0] << " " << q[1] << " " << q[2] << " " << q[3] << " 255 0 0\n";
  }
  return out.str();
}

// --- readers on every variant ---------------------------------------------------------------

TEST(MeshReader, PlyAsciiPlain) {
  const auto path = write_file(scratch_dir() / "cube.ply", ply_ascii_cube(false));
  const TriangleMesh mesh = read_ply_mesh(path);
  expect_same_indexed_mesh(mesh, expected_cube());
  EXPECT_FALSE(mesh.has_vertex_colors());
  EXPECT_FALSE(mesh.has_vertex_normals());
}

TEST(MeshReader, PlyAsciiWithColorsExtraPropertiesAndElements) {
  const auto path = write_file(scratch_dir() / "cube.ply", ply_ascii_cube(true));
  const TriangleMesh mesh = read_ply_mesh(path);
  expect_same_indexed_mesh(mesh, expected_cube());
  ASSERT_EQ(mesh.vertex_colors.size(), 8u);
  EXPECT_EQ(mesh.vertex_colors[3], (Eigen::Matrix<uint8_t, 3, 1>(30, 60, 90)));
}

TEST(MeshReader, PlyBinaryLittleAndBigEndian) {
  for (const bool big_endian : {false, true}) {
    SCOPED_TRACE(big_endian ? "big endian" : "little endian");
    const auto path = write_file(scratch_dir() / "cube.ply", ply_binary_cube(big_endian));
    const TriangleMesh mesh = read_ply_mesh(path);
    expect_same_indexed_mesh(mesh, expected_cube());
    ASSERT_EQ(mesh.vertex_normals.size(), 8u);
    const Eigen::Vector3d expected_normal = (cube_vertex(5) - 0.5 * (kLo + kHi)).normalized();
    EXPECT_LT((mesh.vertex_normals[5] - expected_normal).norm(), 1e-6);
  }
}

TEST(MeshReader, PlyWithCrLfLineEndings) {
  std::string text = ply_ascii_cube(false);
  std::string crlf;
  for (const char c : text) crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
  const auto path = write_file(scratch_dir() / "cube.ply", crlf);
  expect_same_indexed_mesh(read_ply_mesh(path), expected_cube());
}

TEST(MeshReader, ObjAllCornerFormsAndNegativeIndices) {
  const auto path = write_file(scratch_dir() / "cube.obj", obj_cube());
  expect_same_indexed_mesh(read_obj_mesh(path), expected_cube());
}

TEST(MeshReader, StlAsciiMergesCorners) {
  const auto path = write_file(scratch_dir() / "cube.stl", stl_ascii_cube());
  const TriangleMesh mesh = read_stl_mesh(path);
  EXPECT_EQ(mesh.vertices.size(), 8u);  // 36 corners merged into the 8 cube corners
  EXPECT_EQ(canonical_triangles(mesh), canonical_triangles(expected_cube()));
}

TEST(MeshReader, StlBinaryWhoseHeaderStartsWithSolid) {
  const auto path = write_file(scratch_dir() / "cube.stl", stl_binary_cube());
  const TriangleMesh mesh = read_stl_mesh(path);
  EXPECT_EQ(mesh.vertices.size(), 8u);
  EXPECT_EQ(canonical_triangles(mesh), canonical_triangles(expected_cube()));
}

TEST(MeshReader, StlBinaryPlainHeader) {
  const auto path = write_file(scratch_dir() / "cube.stl", stl_binary_cube("binary STL"));
  EXPECT_EQ(canonical_triangles(read_stl_mesh(path)), canonical_triangles(expected_cube()));
}

TEST(MeshReader, OffWithCommentsColorsAndCountsOnEitherLine) {
  for (const bool same_line : {false, true}) {
    const auto path = write_file(scratch_dir() / "cube.off", off_cube(same_line));
    expect_same_indexed_mesh(read_off_mesh(path), expected_cube());
  }
}

TEST(MeshReader, CubeInAllFourFormatsIsTheSameMesh) {
  const auto dir = scratch_dir();
  const auto expected = canonical_triangles(expected_cube());
  // Upper-case extensions: dispatch is case-insensitive.
  for (const auto& [name, bytes] :
       std::vector<std::pair<std::string, std::string>>{{"cube.PLY", ply_binary_cube(false)},
                                                        {"cube.Obj", obj_cube()},
                                                        {"cube.STL", stl_binary_cube()},
                                                        {"cube.off", off_cube(false)}}) {
    SCOPED_TRACE(name);
    const TriangleMesh mesh = read_mesh(write_file(dir / name, bytes));
    EXPECT_EQ(mesh.vertices.size(), 8u);
    EXPECT_EQ(canonical_triangles(mesh), expected);
  }
}

// --- hostile files --------------------------------------------------------------------------

void expect_error(const std::filesystem::path& path, const std::string& fragment) {
  const std::string message = error_of([&] { read_mesh(path); });
  ASSERT_FALSE(message.empty()) << "no error for " << path;
  EXPECT_NE(message.find(path.string()), std::string::npos) << message;
  EXPECT_NE(message.find(fragment), std::string::npos)
      << "message: " << message << "\nexpected to contain: " << fragment;
}

std::string replace(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

TEST(MeshReaderErrors, PlyTruncated) {
  const auto dir = scratch_dir();
  const std::string ascii = ply_ascii_cube(false);
  // Header is 10 lines; keep 5 of the 8 vertex lines.
  size_t cut = 0;
  for (int lines = 0; lines < 15; ++lines) cut = ascii.find('\n', cut) + 1;
  expect_error(write_file(dir / "a.ply", ascii.substr(0, cut)),
               ":15: truncated: element 'vertex' declares 8 items, the file ends after 5");
  const std::string binary = ply_binary_cube(false);
  expect_error(write_file(dir / "b.ply", binary.substr(0, binary.size() - 10)),
               "truncated binary data: element 'material'");
  expect_error(write_file(dir / "c.ply", binary.substr(0, 40)), "no 'end_header'");
}

TEST(MeshReaderErrors, PlyDataLeftOverAfterTheDeclaredElements) {
  const auto dir = scratch_dir();
  const std::string ascii = ply_ascii_cube(false);
  EXPECT_NO_THROW(read_ply_mesh(write_file(dir / "blank.ply", ascii + "\n  \n")));
  expect_error(write_file(dir / "a.ply", ascii + "0 0 0\n"),
               ":25: data left over after every element the header declares");
  const std::string binary = ply_binary_cube(false);
  expect_error(write_file(dir / "b.ply", binary + "xyz"),
               "3 bytes left over after every element the header declares");
}

TEST(MeshReaderErrors, PlyHostileCountsDoNotAllocate) {
  const auto dir = scratch_dir();
  std::string binary =
      replace(ply_binary_cube(false), "element vertex 8", "element vertex 99999999");
  expect_error(write_file(dir / "a.ply", binary), "truncated binary data: element 'vertex'");
  std::string huge =
      replace(ply_binary_cube(false), "element vertex 8", "element vertex 9000000000");
  expect_error(write_file(dir / "b.ply", huge), "too many");
  // An element without properties takes no bytes, whatever its count (this used to spin).
  std::string empty_element = replace(ply_binary_cube(false), "end_header",
                                      "element marker 9223372036854775807\nend_header");
  EXPECT_EQ(read_ply_mesh(write_file(dir / "d.ply", empty_element)).faces.size(), 12u);
  // A face list claiming 200 corners in a file that has fewer bytes left.
  std::string ascii = replace(ply_ascii_cube(false), "4 0 2 3 1", "200 0 2 3 1");
  expect_error(write_file(dir / "c.ply", ascii),
               ":19: list 'vertex_indices' has an impossible length 200");
}

TEST(MeshReaderErrors, PlyIndexOutOfRange) {
  const auto dir = scratch_dir();
  // Line 19 is the first face (10 header lines + 8 vertices).
  expect_error(write_file(dir / "a.ply", replace(ply_ascii_cube(false), "4 0 2 3 1", "4 0 2 8 1")),
               ":19: face 0: vertex index 8 out of range (the file has 8 vertices)");
  expect_error(write_file(dir / "b.ply", replace(ply_ascii_cube(false), "4 0 2 3 1", "4 0 -2 3 1")),
               "vertex index -2 out of range");
}

TEST(MeshReaderErrors, PlyNanCoordinate) {
  const auto dir = scratch_dir();
  std::string text = replace(ply_ascii_cube(false), "3 0.5 2\n", "3 nan 2\n");  // vertex 1, line 12
  expect_error(write_file(dir / "a.ply", text), ":12: vertex 1 has a non-finite coordinate");
  std::string binary = ply_binary_cube(true);
  const size_t first_vertex = binary.find("end_header\n") + 11;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::string nan_bytes;
  append_binary(&nan_bytes, nan, true);
  binary.replace(first_vertex + 8, 8, nan_bytes);  // vertex 0, y
  expect_error(write_file(dir / "b.ply", binary), "vertex 0 has a non-finite coordinate");
}

TEST(MeshReaderErrors, PlyNoFacesAndBadHeaders) {
  const auto dir = scratch_dir();
  std::string no_faces = ply_ascii_cube(false);
  no_faces = replace(no_faces, "element face 6", "element face 0");
  no_faces = no_faces.substr(0, no_faces.find("4 0 2 3 1"));
  expect_error(write_file(dir / "a.ply", no_faces), "mesh has no faces");
  expect_error(write_file(dir / "b.ply", "plyx\n"), ":1: not a PLY file");
  expect_error(write_file(dir / "c.ply", replace(ply_ascii_cube(false), "float x", "float32x x")),
               ":5: unknown PLY property type 'float32x'");
  expect_error(write_file(dir / "d.ply", replace(ply_ascii_cube(false), "property float z\n", "")),
               "no x, y and z");
  expect_error(write_file(dir / "e.ply", replace(ply_ascii_cube(false), "3 0.5 2\n", "3 0.5\n")),
               ":12: too few values");
  expect_error(
      write_file(dir / "f.ply", replace(ply_ascii_cube(false), "3 0.5 2\n", "3 0.5 2 9\n")),
      ":12: expected 3 values, got 4");
  expect_error(
      write_file(dir / "g.ply", replace(ply_ascii_cube(false), "3 0.5 2\n", "3 0.5 two\n")),
      ":12: property 'z': expected a number, got 'two'");
}

TEST(MeshReaderErrors, ObjBadInput) {
  const auto dir = scratch_dir();
  const std::string obj = obj_cube();
  // Faces start at line 21 (3 + 8 v + 4 vt + 2 vn + 3 group lines = 20 lines before).
  expect_error(write_file(dir / "a.obj", replace(obj, "f 1 3 4 2", "f 1 3 9 2")),
               ":21: vertex index 9 out of range (8 vertices defined before this line)");
  expect_error(write_file(dir / "b.obj", replace(obj, "f -8 -4 -2 -6", "f -9 -4 -2 -6")),
               ":25: vertex index -9 out of range");
  expect_error(write_file(dir / "c.obj", replace(obj, "f 5/1 6/2", "f 5/5 6/2")),
               ":22: texture coordinate index 5 out of range (4 texture coordinates");
  expect_error(write_file(dir / "d.obj", replace(obj, "f 1 3 4 2", "f 0 3 4 2")),
               ":21: face corner '0': expected a non-zero vertex index");
  expect_error(write_file(dir / "e.obj", replace(obj, "v 3 0.5 2\n", "v 3 NaN 2\n")),
               ":5: vertex has a non-finite coordinate");
  expect_error(write_file(dir / "f.obj", replace(obj, "f 1 3 4 2", "f 1 3")),
               ":21: face has 2 corners");
  expect_error(write_file(dir / "g.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"), "mesh has no faces");
  // Cut in the middle of a vertex line.
  expect_error(write_file(dir / "h.obj", obj.substr(0, obj.find("v 3 0.5 2") + 6)),
               ":5: expected 'v x y z'");
}

TEST(MeshReaderErrors, StlBadInput) {
  const auto dir = scratch_dir();
  const std::string binary = stl_binary_cube();
  expect_error(write_file(dir / "a.stl", binary.substr(0, binary.size() - 10)),
               "truncated or corrupt binary STL: the header declares 12 triangles (684 bytes) but "
               "the file has 674 bytes");
  expect_error(write_file(dir / "b.stl", stl_binary_cube("binary").substr(0, 50)),
               "shorter than the 84-byte header");
  std::string nan_stl = binary;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(&nan_stl[84 + 3 * 50 + 12 + 4], &nan, 4);  // triangle 3, first corner y
  expect_error(write_file(dir / "c.stl", nan_stl), "triangle 3 (byte 234) has a non-finite");
  const std::string ascii = stl_ascii_cube();
  expect_error(write_file(dir / "d.stl", ascii.substr(0, ascii.find("endloop", 500))),
               "truncated: the facet that starts at line");
  expect_error(write_file(dir / "e.stl", ascii.substr(0, ascii.rfind("endsolid"))),
               "truncated: no 'endsolid'");
  expect_error(write_file(dir / "f.stl", "solid empty\nendsolid empty\n"), "mesh has no faces");
  expect_error(write_file(dir / "g.stl", replace(ascii, "vertex -1 0.5 2", "vertex -1 0.5 inf")),
               ":4: vertex has a non-finite coordinate");
}

TEST(MeshReaderErrors, OffBadInput) {
  const auto dir = scratch_dir();
  const std::string off = off_cube(false);  // vertices on lines 4-11, faces on 12-17
  expect_error(write_file(dir / "a.off", off.substr(0, off.rfind("4 1 3 7 5"))),
               "truncated: expected 6 faces, the file ends after 5");
  expect_error(write_file(dir / "b.off", replace(off, "4 0 2 3 1", "4 0 2 3 12")),
               ":12: vertex index 12 out of range (the file has 8 vertices)");
  expect_error(write_file(dir / "c.off", replace(off, "3 0.5 2\n", "3 nan 2\n")),
               ":5: vertex has a non-finite coordinate");
  expect_error(write_file(dir / "d.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n"), "mesh has no faces");
  expect_error(write_file(dir / "e.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n"),
               ":6: expected a face 'n i1 ... in' with n >= 3, got '2'");
  expect_error(write_file(dir / "f.off", "OFF BINARY\n"), "binary OFF is not supported");
}

TEST(MeshReaderErrors, UnknownExtensionAndMissingFile) {
  const auto dir = scratch_dir();
  expect_error(write_file(dir / "cube.xyz", "x"), "unknown mesh extension '.xyz'");
  expect_error(dir / "absent.ply", "cannot open file");
}

}  // namespace
}  // namespace keel::io
