// Images one at a time from an image folder (index.csv + PNG) or a bag topic
// (sensor_msgs/Image, sensor_msgs/CompressedImage). Pixels are decoded only when asked for.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "core/time.h"
#include "worker/io/folder_index.h"
#include "worker/io/image_header.h"

namespace keel::io {

struct ImageFrame {
  TimeNs t_ns = 0;
  int width = 0;
  int height = 0;
  int channels = 0;   // 1 gray, 3 RGB
  int bit_depth = 0;  // 8 or 16
  // Row-major, interleaved, tightly packed (RGB order); empty unless decoded.
  std::vector<uint8_t> pixels;
};

// Width, height, channels and depth from a PNG's IHDR chunk, without decoding. Fails naming
// the file when it is not a PNG or is truncated.
ImageFrame read_png_info(const std::filesystem::path& path);
// Decodes an encoded image (PNG, JPEG) into gray or RGB (image_codec.h). Throws IoError naming
// `source` for anything else, a header without a size, more than `max_pixels` pixels
// (image_header.h), or what the codec refuses.
ImageFrame decode_image(const std::vector<uint8_t>& encoded, const std::string& source,
                        uint64_t max_pixels = kMaxImagePixels);
ImageFrame read_png(const std::filesystem::path& path);
// Writes 8-bit gray or RGB pixels as PNG (libpng).
void write_png(const std::filesystem::path& path, const ImageFrame& image);

class ImageSource {
 public:
  virtual ~ImageSource() = default;
  virtual size_t size() const = 0;
  // Next image's stamp and size; pixels too when `decode`. False after the last one.
  virtual bool next(ImageFrame& frame, bool decode) = 0;
  virtual std::string current_source() const = 0;
};

class ImageFolderReader : public ImageSource {
 public:
  explicit ImageFolderReader(const std::filesystem::path& folder);
  size_t size() const override { return entries_.size(); }
  bool next(ImageFrame& frame, bool decode) override;
  std::string current_source() const override;

 private:
  std::vector<IndexEntry> entries_;
  size_t next_ = 0;
};

}  // namespace keel::io
