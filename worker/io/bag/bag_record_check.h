// Checks of a ROS1 bag's structure before Debian's rosbag reads it: rosbag trusts every length
// and position the file holds (fuzz_bag found heap-buffer-overflows in ros::Header::parse and
// an out-of-bounds read through an index entry). ROS bag format 2.0
// (wiki.ros.org/Bags/Format/2.0): the magic line "#ROSBAG V2.0\n", then records, each a
// little-endian uint32 header length, the header (fields, each a uint32 length then
// "name=value"), a uint32 data length and the data. Checked: every record and header field,
// and every connection record's connection header (the same field format), lies inside its
// container; each chunk, stored or decompressed as rosbag does (bz2, lz4), is exactly as long
// as its `size` field (at most 1 GiB) and holds whole records; every index entry points at a
// record of the chunk before it; every chunk info's chunk_pos at a chunk and the bag header's
// index_pos at a record. Compressed chunks are so decompressed twice (here and by rosbag).
#pragma once

#include <filesystem>

namespace keel::io {

// Throws IoError naming the file, the record's byte offset and what is wrong.
void check_bag_records(const std::filesystem::path& path);

}  // namespace keel::io
