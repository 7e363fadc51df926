// The kind and pixel size of an encoded camera image, read from its header before a codec sees
// it. OpenCV's imdecode allocates the whole image from the header's size and libjpeg "decodes"
// a file cut short by filling the rest: a 1 KB JPEG declaring 30000 x 30000 pixels became
// 2.7 GB, then two more copies (BGR to RGB, the frame). Keel checks the size first.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>

namespace keel::io {

enum class ImageKind { kPng, kJpeg };

// Pixels (width x height) an image may have: 2^26 (8192 x 8192), above the 61 MP of today's
// largest survey cameras.
constexpr uint64_t kMaxImagePixels = uint64_t{1} << 26;

// PNG by its 8-byte signature, JPEG by FF D8 FF; nothing for anything else.
std::optional<ImageKind> image_kind(const uint8_t* data, size_t size);

struct ImageSize {
  uint32_t width = 0;
  uint32_t height = 0;
};
// PNG: the IHDR chunk (which must come first). JPEG: the first start-of-frame segment (SOF0 to
// SOF15 but DHT, JPG and DAC), found by walking the marker segments as libjpeg does (bytes
// that are not a marker skipped, a length under 2 read past). Nothing when no size comes
// before the image data or the end: decode_image refuses such a file, whatever a lenient codec
// would make of it.
std::optional<ImageSize> read_image_size(const uint8_t* data, size_t size);

}  // namespace keel::io
