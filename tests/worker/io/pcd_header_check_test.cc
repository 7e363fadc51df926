// PCD headers checked before PCL reads them (pcd_header_check.h): what the PCD specification
// allows passes, and each way PCL was made to crash or allocate without bound is refused,
// naming the file and the field or line.
#include "worker/io/cloud/pcd_header_check.h"

#include <gtest/gtest.h>

#include <functional>

#include "worker/io/io_error.h"

namespace keel::io {
namespace {

void expect_refused(const std::string& head, uint64_t file_size,
                    std::initializer_list<std::string> needles) {
  try {
    check_pcd_header(head, file_size, "scan.pcd");
    ADD_FAILURE() << "accepted:\n" << head;
  } catch (const IoError& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind("scan.pcd: ", 0), 0u) << message;
    for (const std::string& needle : needles)
      EXPECT_NE(message.find(needle), std::string::npos) << "'" << needle << "' not in " << message;
  }
}

const std::string kXyz = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n";

TEST(PcdHeaderCheck, SpecificationHeadersPass) {
  // 100 points of 12 bytes need 1200 bytes of binary, 300 of ascii (a byte a value), and
  // 1200 / 88 of LZF.
  const std::string grid = "WIDTH 100\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 100\n";
  EXPECT_NO_THROW(check_pcd_header("# .PCD v0.7\n" + kXyz + grid + "DATA binary\n", 1300, "a"));
  EXPECT_NO_THROW(check_pcd_header(kXyz + grid + "DATA ascii\n", 400, "a"));
  EXPECT_NO_THROW(check_pcd_header(kXyz + grid + "DATA binary_compressed\n", 14 + 100, "a"));
  // v0.5: no SIZE, TYPE or COUNT (4-byte floats, one value each); an organized 10 x 10 grid.
  EXPECT_NO_THROW(check_pcd_header("FIELDS x y z\nWIDTH 10\nHEIGHT 10\nDATA binary\n", 1300, "a"));
  // Lines ended in "\r\n".
  EXPECT_NO_THROW(check_pcd_header(
      "FIELDS x y z\r\nSIZE 4 4 4\r\nTYPE F F F\r\nCOUNT 1 1 1\r\nPOINTS 100\r\nDATA binary\r\n",
      1300, "a"));
  // A field of 33 values (a descriptor) of 8 bytes: 264 bytes a point.
  EXPECT_NO_THROW(check_pcd_header(
      "FIELDS d\nSIZE 8\nTYPE F\nCOUNT 33\nWIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA binary\n", 600, "a"));
}

TEST(PcdHeaderCheck, PointsBeyondTheFileAreRefusedBeforePclAllocatesThem) {
  // PCL's readHeader resizes the cloud to POINTS x the point size before reading the body:
  // a POINTS of 2^32 - 1 in a 200-byte file asked ASan for 5e18 bytes (fuzz_scan_file).
  expect_refused(kXyz + "WIDTH 4294967295\nHEIGHT 1\nPOINTS 4294967295\nDATA binary\n", 200,
                 {"truncated PCD", "4294967295 points of 12 bytes", "200 bytes"});
  expect_refused(kXyz + "WIDTH 101\nHEIGHT 1\nPOINTS 101\nDATA binary\n", 1200,
                 {"truncated PCD", "101 points"});
  expect_refused(kXyz + "WIDTH 401\nHEIGHT 1\nPOINTS 401\nDATA ascii\n", 1200,
                 {"truncated PCD", "401 points of 3 values"});
  expect_refused(kXyz + "WIDTH 9000\nHEIGHT 1\nPOINTS 9000\nDATA binary_compressed\n", 1200,
                 {"9000 points", "LZF"});
  // WIDTH x HEIGHT counts as well as POINTS.
  expect_refused(kXyz + "WIDTH 65536\nHEIGHT 65536\nPOINTS 1\nDATA binary\n", 1200,
                 {"4294967296 points"});
  // Numbers that are not unsigned 32-bit integers (the fuzzer's was 17777777777777777777 with
  // bytes after it, which PCL's stream read in part).
  expect_refused(kXyz + "POINTS 17777777777777777777\nDATA binary\n", 1200, {"POINTS is"});
  expect_refused(kXyz + "POINTS 12x\nDATA binary\n", 1200, {"POINTS is '12x'"});
  expect_refused(kXyz + "WIDTH -1\nDATA binary\n", 1200, {"WIDTH is '-1'"});
  expect_refused(kXyz + "HEIGHT 1 2\nDATA binary\n", 1200, {"HEIGHT is"});
}

TEST(PcdHeaderCheck, FieldsSizesTypesAndCountsFollowTheSpecification) {
  const std::string tail = "WIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA binary\n";
  // A negative SIZE made PCL place the next field at byte 2^32 - 4 (fuzz_scan_file).
  expect_refused("FIELDS x y\nSIZE -4 8\n" + tail, 100, {"SIZE of field 'x' is '-4'"});
  expect_refused("FIELDS x y\nSIZE 4 3\n" + tail, 100, {"SIZE of field 'y' is '3'"});
  expect_refused("FIELDS x y\nTYPE F D\n" + tail, 100, {"TYPE of field 'y' is 'D'"});
  // A COUNT of 2^32 - 1 took PCL 10 s and gigabytes; an overflowing one wrapped its 32-bit
  // point size (fuzz_scan_file).
  expect_refused("FIELDS x y\nCOUNT 1 4294967295\n" + tail, 100, {"COUNT value 2 is '4294967295'"});
  expect_refused("FIELDS x y\nCOUNT 1 0\n" + tail, 100, {"COUNT value 2 is '0'"});
  expect_refused("FIELDS x y z\nSIZE 4 4\n" + tail, 100, {"SIZE has 2 values for 3 FIELDS"});
  expect_refused("FIELDS x\nFIELDS x y\n" + tail, 100, {"FIELDS is given twice"});
  expect_refused("FIELDS\n" + tail, 100, {"FIELDS has no values"});
  expect_refused("SIZE 4\n" + tail, 100, {"no FIELDS"});
  expect_refused("FIELDS x\nSIZE 4\n", 100, {"no DATA line"});
  // Keywords match by prefix, as in PCL: a "COUNTS" line is PCL's COUNT line.
  expect_refused("FIELDS x\nCOUNTS 4294967295\n" + tail, 100, {"COUNT value 1"});
  // Comment lines are not read.
  EXPECT_NO_THROW(check_pcd_header("# COUNT 0\nFIELDS x\n" + tail, 100, "a"));
}

TEST(PcdHeaderCheck, TheHeaderEndsAtTheFirstLineThatIsNotAKeywordNotAtData) {
  // PCL goes on reading keywords after DATA: a POINTS line there (found by fuzz_scan_file,
  // "POINTS 2222222222222222979" after "DATA binary_comp...") resized its cloud.
  const std::string head = "FIELDS x\nDATA binary\nPOINTS 99999\n";
  expect_refused(head, 200, {"truncated PCD", "99999 points"});
  expect_refused("FIELDS x\nDATA binary\nDATA ascii\n1\n", 200, {"DATA is given twice"});
  // The body's first line ends the header: what follows is data, whatever it says.
  EXPECT_NO_THROW(check_pcd_header("FIELDS x\nPOINTS 2\nDATA ascii\n1\nPOINTS 99999\n", 200, "a"));
  // A header line before DATA that is not a keyword ends the header too: no DATA then.
  expect_refused("FIELDS x\nPOINTS 2\nhello\nDATA ascii\n1\n2\n", 200, {"no DATA line"});
  // Only the first 64 KiB are read: a header still going there is refused, a body is not.
  std::string long_head = "FIELDS x\nDATA binary\n";
  while (long_head.size() < kPcdHeaderBytes) long_head += "# a comment line\n";
  expect_refused(long_head.substr(0, kPcdHeaderBytes), 1 << 20, {"runs past its first 64 KiB"});
  std::string body = "FIELDS x\nPOINTS 20000\nDATA binary\n";
  body += std::string(kPcdHeaderBytes - body.size(), '\0');  // no newline in the data read
  EXPECT_NO_THROW(check_pcd_header(body, 80100, "a"));
}

}  // namespace
}  // namespace keel::io
