// ROS1 bag chunks (worker/io/bag/ros1_chunk.h) compressed by the libraries' own compressors
// (libbz2's BZ2_bzBuffToBuffCompress, liblz4's LZ4F_compressFrame: roslz4 writes LZ4 frames)
// decompress to their bytes; a chunk whose `size` says more or less than its stream holds, a
// cut stream, an unknown compression or a size over the limit are refused naming the record;
// and a few bytes claiming a gigabyte allocate no more than they decompress to.
#include "worker/io/bag/ros1_chunk.h"

#include <bzlib.h>
#include <gtest/gtest.h>
#include <lz4frame.h>

#include <string>
#include <vector>

#include "worker/io/bag/bag_format_error.h"

namespace keel::io {
namespace {

std::vector<uint8_t> records(size_t n) {
  std::vector<uint8_t> out(n);
  for (size_t i = 0; i < n; ++i) out[i] = static_cast<uint8_t>((i * 7919) % 251);
  return out;
}

std::vector<uint8_t> bz2(const std::vector<uint8_t>& in) {
  unsigned int size = static_cast<unsigned int>(in.size() + in.size() / 100 + 600);
  std::vector<uint8_t> out(size);
  char empty = 0;  // libbz2 refuses a null source, even of 0 bytes
  EXPECT_EQ(BZ2_bzBuffToBuffCompress(
                reinterpret_cast<char*>(out.data()), &size,
                in.empty() ? &empty : reinterpret_cast<char*>(const_cast<uint8_t*>(in.data())),
                static_cast<unsigned int>(in.size()), 9, 0, 0),
            BZ_OK);
  out.resize(size);
  return out;
}

std::vector<uint8_t> lz4(const std::vector<uint8_t>& in) {
  std::vector<uint8_t> out(LZ4F_compressFrameBound(in.size(), nullptr));
  const size_t size = LZ4F_compressFrame(out.data(), out.size(), in.data(), in.size(), nullptr);
  EXPECT_FALSE(LZ4F_isError(size));
  out.resize(size);
  return out;
}

std::string refusal(const std::string& compression, const std::vector<uint8_t>& stored,
                    uint32_t size, std::vector<uint8_t>* out_seen = nullptr) {
  std::vector<uint8_t> out;
  try {
    decompress_ros1_chunk(compression, stored, size, "b.bag: record at byte 9", out);
  } catch (const BagFormatError& e) {
    if (out_seen) *out_seen = std::move(out);
    return e.what();
  }
  return "accepted";
}

TEST(Ros1Chunk, EachCompressionGivesItsBytes) {
  for (size_t n : {size_t(0), size_t(1), size_t(1000), size_t(3 << 20)}) {
    SCOPED_TRACE(n);
    const std::vector<uint8_t> plain = records(n);
    std::vector<uint8_t> out;
    decompress_ros1_chunk("none", plain, static_cast<uint32_t>(n), "w", out);
    EXPECT_EQ(out, plain);
    decompress_ros1_chunk("bz2", bz2(plain), static_cast<uint32_t>(n), "w", out);
    EXPECT_EQ(out, plain);
    decompress_ros1_chunk("lz4", lz4(plain), static_cast<uint32_t>(n), "w", out);
    EXPECT_EQ(out, plain);
  }
}

TEST(Ros1Chunk, SizesThatDisagreeWithTheStreamAreRefused) {
  const std::vector<uint8_t> plain = records(5000);
  for (const char* compression : {"none", "bz2", "lz4"}) {
    SCOPED_TRACE(compression);
    const std::vector<uint8_t> stored = std::string(compression) == "bz2"   ? bz2(plain)
                                        : std::string(compression) == "lz4" ? lz4(plain)
                                                                            : plain;
    EXPECT_EQ(refusal(compression, stored, 4999),
              "b.bag: record at byte 9: chunk holds more than 4999 bytes uncompressed; its "
              "'size' field says 4999")
        << compression;
    const std::string more = refusal(compression, stored, 5001);
    EXPECT_EQ(more,
              "b.bag: record at byte 9: chunk holds 5000 bytes uncompressed; its 'size' field "
              "says 5001");
  }
}

// A stream of a few hundred bytes that claims 1 GiB: refused once the stream ends, having
// allocated about what it produced.
TEST(Ros1Chunk, AHugeClaimAllocatesOnlyWhatTheStreamHolds) {
  const std::vector<uint8_t> plain = records(1000);
  for (const char* compression : {"bz2", "lz4"}) {
    SCOPED_TRACE(compression);
    const std::vector<uint8_t> stored = std::string(compression) == "bz2" ? bz2(plain) : lz4(plain);
    std::vector<uint8_t> out;
    EXPECT_EQ(refusal(compression, stored, kMaxRos1ChunkBytes, &out),
              "b.bag: record at byte 9: chunk holds 1000 bytes uncompressed; its 'size' field "
              "says 1073741824");
    EXPECT_LE(out.capacity(), size_t(1) << 20);
  }
  EXPECT_EQ(refusal("bz2", bz2(plain), kMaxRos1ChunkBytes + 1),
            "b.bag: record at byte 9: chunk declares 1073741825 bytes uncompressed; Keel reads "
            "chunks of up to 1073741824 bytes");
}

TEST(Ros1Chunk, CutAndCorruptStreamsAndUnknownCompressionsAreRefused) {
  const std::vector<uint8_t> plain = records(100000);
  std::vector<uint8_t> cut = bz2(plain);
  cut.resize(cut.size() / 2);
  EXPECT_EQ(refusal("bz2", cut, 100000),
            "b.bag: record at byte 9: bz2 chunk ends before its stream does");
  cut = lz4(plain);
  cut.resize(cut.size() / 2);
  EXPECT_EQ(refusal("lz4", cut, 100000),
            "b.bag: record at byte 9: lz4 chunk ends before its frame does");
  std::vector<uint8_t> garbage = records(64);
  EXPECT_NE(refusal("bz2", garbage, 64).find("bz2 chunk does not decompress (bzip2 error"),
            std::string::npos);
  EXPECT_NE(refusal("lz4", garbage, 64).find("lz4 chunk does not decompress ("), std::string::npos);
  EXPECT_EQ(refusal("zstd", garbage, 64),
            "b.bag: record at byte 9: chunk compression 'zstd' (expected none, lz4 or bz2)");
}

}  // namespace
}  // namespace keel::io
