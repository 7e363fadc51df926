// PNG and JPEG through libpng and libjpeg(-turbo) directly: the two formats Keel reads. OpenCV's
// imgcodecs brought in GDAL and ~140 shared libraries that every keel-worker start paid for.
// Both decoders run only on bytes whose signature and size image_header.h has checked.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace keel::io {

struct DecodedImage {
  int width = 0;
  int height = 0;
  int channels = 0;             // 1 gray, 3 RGB (alpha dropped, palettes expanded)
  int bit_depth = 0;            // 8, or 16 for 16-bit PNG (native-endian uint16 samples)
  std::vector<uint8_t> pixels;  // row-major, interleaved, tightly packed
};

// Each throws IoError naming `source` and the codec's own message for what it refuses, a
// truncated file included.
DecodedImage decode_png(const uint8_t* data, size_t size, const std::string& source);
DecodedImage decode_jpeg(const uint8_t* data, size_t size, const std::string& source);

// 8-bit gray (1 channel) or RGB (3) pixels as a PNG file's bytes.
std::string encode_png(const uint8_t* pixels, int width, int height, int channels);

}  // namespace keel::io
