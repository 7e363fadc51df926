#include "worker/io/bag/ros1_chunk.h"

#include <bzlib.h>
#include <lz4frame.h>

#include <algorithm>
#include <memory>

#include "worker/io/bag/bag_format_error.h"

namespace keel::io {
namespace {

// Room for more output: doubles what is there (at least 64 KiB), up to one byte past `size`
// so that a stream longer than its chunk says is seen.
void grow(std::vector<uint8_t>& out, size_t produced, uint32_t size) {
  const size_t limit = size_t(size) + 1;
  out.resize(std::min(limit, std::max<size_t>(2 * produced, produced + (64u << 10))));
}

size_t bunzip(const std::vector<uint8_t>& stored, uint32_t size, const std::string& where,
              std::vector<uint8_t>& out) {
  bz_stream stream{};
  if (BZ2_bzDecompressInit(&stream, 0, 0) != BZ_OK)
    throw BagFormatError(where + ": bz2: cannot start the decompressor");
  std::unique_ptr<bz_stream, int (*)(bz_stream*)> end(&stream, BZ2_bzDecompressEnd);
  stream.next_in = reinterpret_cast<char*>(const_cast<uint8_t*>(stored.data()));
  stream.avail_in = static_cast<unsigned int>(stored.size());
  size_t produced = 0;
  for (;;) {
    if (produced == out.size()) {
      if (out.size() > size) break;  // one byte past `size`: longer than the chunk says
      grow(out, produced, size);
    }
    stream.next_out = reinterpret_cast<char*>(out.data() + produced);
    stream.avail_out = static_cast<unsigned int>(out.size() - produced);
    const int rc = BZ2_bzDecompress(&stream);
    produced = out.size() - stream.avail_out;
    if (rc == BZ_STREAM_END) break;
    if (rc != BZ_OK)
      throw BagFormatError(where + ": bz2 chunk does not decompress (bzip2 error " +
                           std::to_string(rc) + ")");
    if (stream.avail_in == 0 && stream.avail_out > 0)
      throw BagFormatError(where + ": bz2 chunk ends before its stream does");
  }
  return produced;
}

size_t unlz4(const std::vector<uint8_t>& stored, uint32_t size, const std::string& where,
             std::vector<uint8_t>& out) {
  LZ4F_dctx* context = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&context, LZ4F_VERSION)))
    throw BagFormatError(where + ": lz4: cannot start the decompressor");
  std::unique_ptr<LZ4F_dctx, LZ4F_errorCode_t (*)(LZ4F_dctx*)> end(context,
                                                                   LZ4F_freeDecompressionContext);
  size_t consumed = 0, produced = 0;
  for (;;) {
    if (produced == out.size()) {
      if (out.size() > size) break;
      grow(out, produced, size);
    }
    size_t out_size = out.size() - produced;
    size_t in_size = stored.size() - consumed;
    const size_t hint = LZ4F_decompress(context, out.data() + produced, &out_size,
                                        stored.data() + consumed, &in_size, nullptr);
    if (LZ4F_isError(hint))
      throw BagFormatError(where + ": lz4 chunk does not decompress (" + LZ4F_getErrorName(hint) +
                           ")");
    consumed += in_size;
    produced += out_size;
    if (hint == 0) break;  // the frame is complete
    if (consumed == stored.size() && produced < out.size())
      throw BagFormatError(where + ": lz4 chunk ends before its frame does");
  }
  return produced;
}

}  // namespace

void decompress_ros1_chunk(const std::string& compression, const std::vector<uint8_t>& stored,
                           uint32_t size, const std::string& where, std::vector<uint8_t>& out) {
  if (size > kMaxRos1ChunkBytes)
    throw BagFormatError(where + ": chunk declares " + std::to_string(size) +
                         " bytes uncompressed; Keel reads chunks of up to " +
                         std::to_string(kMaxRos1ChunkBytes) + " bytes");
  out.clear();
  size_t produced = 0;
  if (compression == "none") {
    out = stored;
    produced = out.size();
  } else if (compression == "bz2") {
    produced = bunzip(stored, size, where, out);
  } else if (compression == "lz4") {
    produced = unlz4(stored, size, where, out);
  } else {
    throw BagFormatError(where + ": chunk compression '" + compression +
                         "' (expected none, lz4 or bz2)");
  }
  if (produced != size)
    throw BagFormatError(
        where + ": chunk holds " +
        (produced > size ? "more than " + std::to_string(size) : std::to_string(produced)) +
        " bytes uncompressed; its 'size' field says " + std::to_string(size));
  out.resize(produced);
}

}  // namespace keel::io
