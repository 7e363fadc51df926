// Bounds checks of a ROS1 bag's records before Debian's rosbag reads them: rosbag's
// ros::Header::parse trusts each header field's length (a heap-buffer-overflow on a crafted
// bag, found by fuzz_bag). ROS bag format 2.0 (wiki.ros.org/Bags/Format/2.0): the magic line
// "#ROSBAG V2.0\n", then records, each a little-endian uint32 header length, the header (fields,
// each a uint32 length then "name=value"), a uint32 data length and the data. Records inside
// an uncompressed chunk have the same layout and are checked too; those inside a bz2 or lz4
// chunk are left to rosbag.
#pragma once

#include <filesystem>

namespace keel::io {

// Throws IoError naming the file, the record's byte offset and what is wrong when a record
// (or a field of its header) runs past its container, or a field has no '='.
void check_bag_records(const std::filesystem::path& path);

}  // namespace keel::io
