#include "worker/io/image_header.h"

#include <algorithm>
#include <cstring>

namespace keel::io {
namespace {

const uint8_t kPngSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
const uint8_t kJpegSignature[3] = {0xff, 0xd8, 0xff};

uint32_t big_endian32(const uint8_t* p) {
  return (uint32_t(p[0]) << 24) | (uint32_t(p[1]) << 16) | (uint32_t(p[2]) << 8) | uint32_t(p[3]);
}
uint32_t big_endian16(const uint8_t* p) { return (uint32_t(p[0]) << 8) | uint32_t(p[1]); }

// PNG: signature, then the IHDR chunk: length (4), "IHDR", width (4), height (4).
std::optional<ImageSize> png_size(const uint8_t* data, size_t size) {
  if (size < 24 || std::memcmp(data + 12, "IHDR", 4) != 0) return std::nullopt;
  return ImageSize{big_endian32(data + 16), big_endian32(data + 20)};
}

// ITU T.81 B.1.1: markers are FF followed by a code (fill FFs may precede it); the standalone
// ones (SOI, RSTn, TEM) carry no length, the others a 16-bit length that counts itself. A
// start-of-frame segment holds precision (1), height (2), width (2).
bool is_start_of_frame(uint8_t code) {
  return code >= 0xc0 && code <= 0xcf && code != 0xc4 && code != 0xc8 && code != 0xcc;
}
bool is_standalone(uint8_t code) {
  return code == 0x01 || code == 0xd8 || (code >= 0xd0 && code <= 0xd7);
}

std::optional<ImageSize> jpeg_size(const uint8_t* data, size_t size) {
  size_t at = 2;  // after SOI
  while (at < size) {
    // libjpeg's next_marker skips anything that is not FF where a marker should be ("Corrupt
    // JPEG data: N extraneous bytes"), and reads the frame after it: so does this walk.
    while (at < size && data[at] != 0xff) ++at;
    while (at < size && data[at] == 0xff) ++at;  // fill bytes
    if (at >= size) return std::nullopt;
    const uint8_t code = data[at++];
    if (is_standalone(code)) continue;
    if (code == 0xd9 || code == 0xda) return std::nullopt;  // EOI or scan data before a frame
    if (at + 2 > size) return std::nullopt;
    if (is_start_of_frame(code)) {
      // libjpeg reads the size before it checks the segment's length.
      if (at + 7 > size) return std::nullopt;
      return ImageSize{big_endian16(data + at + 5), big_endian16(data + at + 3)};
    }
    // A length under 2 moves libjpeg on to the bytes after it, as here.
    at += std::max<size_t>(big_endian16(data + at), 2);
  }
  return std::nullopt;
}

}  // namespace

std::optional<ImageKind> image_kind(const uint8_t* data, size_t size) {
  if (size >= sizeof(kPngSignature) && std::memcmp(data, kPngSignature, sizeof(kPngSignature)) == 0)
    return ImageKind::kPng;
  if (size >= sizeof(kJpegSignature) &&
      std::memcmp(data, kJpegSignature, sizeof(kJpegSignature)) == 0)
    return ImageKind::kJpeg;
  return std::nullopt;
}

std::optional<ImageSize> read_image_size(const uint8_t* data, size_t size) {
  const auto kind = image_kind(data, size);
  if (!kind) return std::nullopt;
  return *kind == ImageKind::kPng ? png_size(data, size) : jpeg_size(data, size);
}

}  // namespace keel::io
