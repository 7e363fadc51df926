// A ROS1 bag chunk's records from its stored bytes (ROS bag format 2.0, "Chunk"): stored as
// they are ("none"), bzip2 ("bz2", through libbz2) or LZ4 ("lz4": roslz4 writes LZ4 frames,
// lz4_Frame_format.md, read through liblz4's frame API). The output buffer grows with what
// the decompressor produces, never to the `size` the chunk claims before it is produced, so a
// few bytes that claim a gigabyte allocate no more than they decompress to.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace keel::io {

// The largest chunk read (rosbag writes 768 KiB chunks by default).
constexpr uint32_t kMaxRos1ChunkBytes = 1u << 30;

// Decompresses `stored` (`compression` as the chunk header names it) into `out`, which must
// then hold exactly `size` bytes. Throws BagFormatError "<where>: ..." on an unknown
// compression, a corrupt stream, a size over kMaxRos1ChunkBytes or another size than `size`.
void decompress_ros1_chunk(const std::string& compression, const std::vector<uint8_t>& stored,
                           uint32_t size, const std::string& where, std::vector<uint8_t>& out);

}  // namespace keel::io
