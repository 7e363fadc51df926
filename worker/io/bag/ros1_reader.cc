#include "worker/io/bag/ros1_reader.h"

#include <string>

#include "worker/io/bag/bag_format_error.h"

namespace keel::io {

void Ros1Reader::overrun(uint64_t bytes, const char* field) const {
  throw BagFormatError("ROS1: field '" + std::string(field) + "' needs " + std::to_string(bytes) +
                       " bytes at offset " + std::to_string(at_) + "; the " +
                       std::to_string(size_) + "-byte message has " + std::to_string(size_ - at_) +
                       " left");
}

}  // namespace keel::io
