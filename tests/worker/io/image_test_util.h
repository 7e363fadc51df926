// Shared by the image tests: OpenCV's own encodings, and decode_image's refusal as text.
#pragma once

#include <opencv2/imgcodecs.hpp>

#include <string>
#include <vector>

#include "tests/error_of.h"
#include "worker/io/image_source.h"
#include "worker/io/io_error.h"

namespace keel::io::image_testing {

inline std::vector<uint8_t> encode(const std::string& ext, const cv::Mat& mat,
                                   const std::vector<int>& params = {}) {
  std::vector<uint8_t> bytes;
  cv::imencode(ext, mat, bytes, params);
  return bytes;
}

// decode_image's IoError message for `bytes` named `source`, or "" when they decode.
inline std::string refusal(const std::vector<uint8_t>& bytes, const std::string& source) {
  return keel::testing::error_of<IoError>([&] { decode_image(bytes, source); });
}

}  // namespace keel::io::image_testing
