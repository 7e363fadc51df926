// The shared PLY header parser: known headers written out by hand (the expected elements,
// types and offsets are counted from the text), and hostile headers that must be refused
// with an IoError naming the file and the line.
#include "worker/io/cloud/ply_header.h"

#include <gtest/gtest.h>

#include <string>

#include "tests/error_of.h"
#include "worker/io/io_error.h"

namespace keel::io {
namespace {

const std::string kFile = "scan.ply";

// The IoError message of parsing `text` ("" when it parses).
std::string error_of(const std::string& text) {
  return keel::testing::error_of<IoError>([&] { parse_ply_header(text, kFile); });
}

void expect_error(const std::string& text, const std::string& where, const std::string& what) {
  const std::string message = error_of(text);
  ASSERT_FALSE(message.empty()) << "no error for:\n" << text;
  EXPECT_EQ(message.rfind(kFile + ":" + where + ": ", 0), 0u) << message;
  EXPECT_NE(message.find(what), std::string::npos) << message << "\nexpected: " << what;
}

TEST(PlyHeader, TypeSizes) {
  EXPECT_EQ(ply_type_size(PlyType::kInt8), 1u);
  EXPECT_EQ(ply_type_size(PlyType::kUint8), 1u);
  EXPECT_EQ(ply_type_size(PlyType::kInt16), 2u);
  EXPECT_EQ(ply_type_size(PlyType::kUint16), 2u);
  EXPECT_EQ(ply_type_size(PlyType::kInt32), 4u);
  EXPECT_EQ(ply_type_size(PlyType::kUint32), 4u);
  EXPECT_EQ(ply_type_size(PlyType::kFloat32), 4u);
  EXPECT_EQ(ply_type_size(PlyType::kFloat64), 8u);
  EXPECT_TRUE(ply_type_is_integer(PlyType::kUint32));
  EXPECT_FALSE(ply_type_is_integer(PlyType::kFloat32));
}

TEST(PlyHeader, AsciiMeshWithScalarsListsAndSeveralElements) {
  const std::string header =
      "ply\n"
      "format ascii 1.0\n"
      "comment made by hand\n"
      "obj_info scanner 7\n"
      "element vertex 8\n"
      "property float x\n"
      "property float32 y\n"
      "property double z\n"
      "property uchar red\n"
      "element face 6\n"
      "property list uchar int vertex_indices\n"
      "element edge 0\n"
      "end_header\n";
  const PlyHeader h = parse_ply_header(header + "0 0 0 1\n", kFile);
  EXPECT_EQ(h.format, PlyFormat::kAscii);
  EXPECT_EQ(h.version, "1.0");
  EXPECT_EQ(h.format_line, 2u);
  ASSERT_EQ(h.comments.size(), 2u);
  EXPECT_EQ(h.comments[0], "made by hand");
  EXPECT_EQ(h.comments[1], "scanner 7");
  EXPECT_EQ(h.end_header_line, 13u);
  EXPECT_EQ(h.body_offset, header.size());

  ASSERT_EQ(h.elements.size(), 3u);
  const PlyElement& vertex = h.elements[0];
  EXPECT_EQ(vertex.name, "vertex");
  EXPECT_EQ(vertex.count, 8u);
  EXPECT_EQ(vertex.line, 5u);
  ASSERT_EQ(vertex.properties.size(), 4u);
  const char* names[] = {"x", "y", "z", "red"};
  const PlyType types[] = {PlyType::kFloat32, PlyType::kFloat32, PlyType::kFloat64,
                           PlyType::kUint8};
  for (size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(vertex.properties[i].name, names[i]);
    EXPECT_EQ(vertex.properties[i].type, types[i]) << i;
    EXPECT_FALSE(vertex.properties[i].is_list);
    EXPECT_EQ(vertex.properties[i].line, 6 + i);
  }
  const PlyElement& face = h.elements[1];
  EXPECT_EQ(face.name, "face");
  EXPECT_EQ(face.count, 6u);
  ASSERT_EQ(face.properties.size(), 1u);
  EXPECT_TRUE(face.properties[0].is_list);
  EXPECT_EQ(face.properties[0].count_type, PlyType::kUint8);
  EXPECT_EQ(face.properties[0].type, PlyType::kInt32);
  EXPECT_EQ(face.properties[0].name, "vertex_indices");
  EXPECT_EQ(h.elements[2].name, "edge");
  EXPECT_EQ(h.elements[2].count, 0u);
  EXPECT_TRUE(h.elements[2].properties.empty());
}

TEST(PlyHeader, BinaryFormatsEveryTypeNameAndCrLf) {
  const std::string types =
      "element v 5000000000\n"
      "property char a\nproperty int8 b\nproperty uchar c\nproperty uint8 d\n"
      "property short e\nproperty int16 f\nproperty ushort g\nproperty uint16 h\n"
      "property int i\nproperty int32 j\nproperty uint k\nproperty uint32 l\n"
      "property float m\nproperty float32 n\nproperty double o\nproperty float64 p\n"
      "property list ushort uint32 q\n"
      "end_header\n";
  const PlyType expected[] = {
      PlyType::kInt8,    PlyType::kInt8,    PlyType::kUint8,   PlyType::kUint8,
      PlyType::kInt16,   PlyType::kInt16,   PlyType::kUint16,  PlyType::kUint16,
      PlyType::kInt32,   PlyType::kInt32,   PlyType::kUint32,  PlyType::kUint32,
      PlyType::kFloat32, PlyType::kFloat32, PlyType::kFloat64, PlyType::kFloat64};
  for (const auto& [name, format] :
       {std::pair{"binary_little_endian", PlyFormat::kBinaryLittleEndian},
        std::pair{"binary_big_endian", PlyFormat::kBinaryBigEndian}}) {
    const std::string header = std::string("ply\nformat ") + name + " 1.0\n" + types;
    // Binary bytes after end_header, including newlines and NULs, are not header.
    const PlyHeader h = parse_ply_header(header + std::string("\n\0\x01", 3), kFile);
    EXPECT_EQ(h.format, format);
    EXPECT_STREQ(to_string(h.format), name);
    EXPECT_EQ(h.body_offset, header.size());
    EXPECT_EQ(h.end_header_line, 21u);
    ASSERT_EQ(h.elements.size(), 1u);
    // Counts beyond 32 bits are kept exactly; readers bound them by the file size.
    EXPECT_EQ(h.elements[0].count, 5000000000u);
    ASSERT_EQ(h.elements[0].properties.size(), 17u);
    for (size_t i = 0; i < 16; ++i) EXPECT_EQ(h.elements[0].properties[i].type, expected[i]) << i;
    EXPECT_EQ(h.elements[0].properties[16].count_type, PlyType::kUint16);
    EXPECT_EQ(h.elements[0].properties[16].type, PlyType::kUint32);
  }
  // A magic line padded with blanks is still PLY.
  EXPECT_EQ(parse_ply_header("ply \t\nformat ascii 1.0\nend_header\n", kFile).format_line, 2u);
  // CRLF line endings and a final end_header without a line ending (an empty body).
  const std::string crlf_text = "ply\r\nformat ascii 1.0\r\nelement vertex 0\r\nend_header";
  const PlyHeader crlf = parse_ply_header(crlf_text, kFile);
  EXPECT_EQ(crlf.end_header_line, 4u);
  ASSERT_EQ(crlf.elements.size(), 1u);
  EXPECT_EQ(crlf.body_offset, crlf_text.size());
}

TEST(PlyHeaderErrors, MagicFormatAndVersion) {
  expect_error("plyx\nformat ascii 1.0\nend_header\n", "1", "not a PLY file");
  expect_error("", "1", "not a PLY file");
  expect_error("ply\nformat ascii\nend_header\n", "2", "expected 'format <ascii|");
  expect_error("ply\nformat binary_middle_endian 1.0\nend_header\n", "2",
               "unknown PLY format 'binary_middle_endian'");
  expect_error("ply\nformat ascii 2.0\nend_header\n", "2", "unsupported PLY version '2.0'");
  expect_error("ply\ncomment x\nelement vertex 1\nend_header\n", "4",
               "PLY header has no 'format' line");
  expect_error("ply\nformat ascii 1.0\nvertices 3\nend_header\n", "3",
               "unknown PLY header keyword 'vertices'");
}

TEST(PlyHeaderErrors, AbsurdCounts) {
  const std::string start = "ply\nformat ascii 1.0\ncomment c\n";
  expect_error(start + "element vertex -1\nend_header\n", "4", "bad count of element 'vertex'");
  expect_error(start + "element vertex 99999999999999999999\nend_header\n", "4",
               "bad count of element 'vertex'");
  expect_error(start + "element vertex 1e9\nend_header\n", "4", "got '1e9'");
  expect_error(start + "element vertex 2.5\nend_header\n", "4", "bad count");
  expect_error(start + "element vertex\nend_header\n", "4", "expected 'element <name> <count>'");
}

TEST(PlyHeaderErrors, PropertiesAndTypes) {
  const std::string start = "ply\nformat binary_little_endian 1.0\nelement vertex 3\n";
  expect_error("ply\nformat ascii 1.0\nproperty float x\nend_header\n", "3",
               "'property' before any 'element'");
  expect_error(start + "property float x\nproperty quad y\nend_header\n", "5",
               "unknown PLY property type 'quad'");
  expect_error(start + "property list uchar complex z\nend_header\n", "4",
               "unknown PLY property type 'complex'");
  expect_error(start + "property list float int z\nend_header\n", "4",
               "list count type must be an integer type, got 'float'");
  expect_error(start + "property float\nend_header\n", "4", "expected 'property <type> <name>'");
  expect_error(start + "property list uchar int\nend_header\n", "4", "expected 'property");
  expect_error(start + "property float x\nproperty float y\nproperty double x\nend_header\n", "6",
               "element 'vertex' declares property 'x' twice (first on line 4)");
  // The same name in different elements is fine.
  EXPECT_EQ(error_of(start + "property float x\nelement other 1\nproperty float x\nend_header\n"),
            "");
}

TEST(PlyHeaderErrors, MissingOrTruncatedEndHeader) {
  const std::string header = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n";
  expect_error(header, "4", "no 'end_header'");
  expect_error(header + "property float y", "5", "no end_header");  // cut mid-header
  expect_error(header + "end_heade\n1\n2\n3\n", "5", "unknown PLY header keyword 'end_heade'");
  expect_error("ply\n", "1", "no 'end_header'");
  expect_error("ply\nformat ascii 1.0\n\n", "3", "no 'end_header'");
}

}  // namespace
}  // namespace keel::io
