// Checks a serialized ROS1 message of a type Keel reads before roscpp_serialization decodes
// it: that deserializer sizes each string and array from its uint32 length prefix before it
// looks whether the message holds that many bytes (fuzz_bag: a PointCloud2 whose `data`
// declared 4 GiB was allocated, then refused). ROS1 serialization (wiki.ros.org/msg):
// little endian, no padding, strings and arrays as a uint32 count then their elements.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace keel::io {

// Throws IoError "<what>: <field> declares N bytes; the message has M left" when a string or
// array of `datatype` (one of the types of docs/mission-format.md's ROS1 table) runs past
// the message. Other types are not checked.
void check_ros1_message(std::string_view datatype, const uint8_t* data, size_t size,
                        const std::string& what);

}  // namespace keel::io
