#include "worker/io/image_source.h"

#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>

#include "core/replaced_file.h"
#include "worker/io/display_path.h"
#include "worker/io/image_codec.h"
#include "worker/io/image_header.h"
#include "worker/io/io_error.h"
#include "worker/io/text_lines.h"

namespace keel::io {

namespace {

ImageFrame to_frame(DecodedImage&& image) {
  ImageFrame frame;
  frame.width = image.width;
  frame.height = image.height;
  frame.channels = image.channels;
  frame.bit_depth = image.bit_depth;
  frame.pixels = std::move(image.pixels);
  return frame;
}

}  // namespace

ImageFrame read_png_info(const std::filesystem::path& path) {
  const std::string file = display_path(path);
  std::unique_ptr<FILE, int (*)(FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!f) throw IoError(file + ": cannot open");
  uint8_t head[33];
  const size_t n = std::fread(head, 1, sizeof(head), f.get());
  if (image_kind(head, n) != ImageKind::kPng) throw IoError(file + ": not a PNG file");
  const auto size = read_image_size(head, n);
  if (n < 33 || !size) throw IoError(file + ": truncated PNG (no IHDR chunk)");
  ImageFrame frame;
  frame.width = static_cast<int>(size->width);
  frame.height = static_cast<int>(size->height);
  frame.bit_depth = head[24];
  switch (head[25]) {  // PNG colour type
    case 0:
      frame.channels = 1;
      break;
    case 2:
      frame.channels = 3;
      break;
    case 3:
      frame.channels = 3;
      break;  // palette, decoded to RGB
    case 4:
      frame.channels = 2;
      break;
    case 6:
      frame.channels = 4;
      break;
    default:
      throw IoError(file + ": bad PNG colour type " + std::to_string(head[25]));
  }
  if (frame.width <= 0 || frame.height <= 0) throw IoError(file + ": PNG with zero size");
  return frame;
}

// Keel reads PNG and JPEG, by signature only (a general decoder that tries every format it
// knows once let DICOM bytes reach a reader that aborts the process), and checks the size
// before a codec allocates for it (image_header.h).
ImageFrame decode_image(const std::vector<uint8_t>& encoded, const std::string& source,
                        uint64_t max_pixels) {
  if (encoded.empty()) throw IoError(source + ": empty image (0 bytes)");
  const auto kind = image_kind(encoded.data(), encoded.size());
  if (!kind)
    throw IoError(source + ": not a PNG or JPEG image (its first bytes are neither signature)");
  if (encoded.size() > static_cast<size_t>(std::numeric_limits<int>::max()))
    throw IoError(source + ": image of " + std::to_string(encoded.size()) + " bytes, over 2 GiB");
  const auto size = read_image_size(encoded.data(), encoded.size());
  if (!size)
    throw IoError(source + (*kind == ImageKind::kPng
                                ? ": PNG without its IHDR chunk (truncated?)"
                                : ": JPEG without a frame header (SOF) before its data"));
  if (uint64_t{size->width} * size->height > max_pixels)
    throw IoError(source + ": image of " + std::to_string(size->width) + " x " +
                  std::to_string(size->height) + " pixels, more than Keel reads (" +
                  std::to_string(max_pixels) + ")");
  return to_frame(*kind == ImageKind::kPng ? decode_png(encoded.data(), encoded.size(), source)
                                           : decode_jpeg(encoded.data(), encoded.size(), source));
}

ImageFrame read_png(const std::filesystem::path& path) {
  const std::string bytes = read_file_bytes(path);
  return decode_image(std::vector<uint8_t>(bytes.begin(), bytes.end()), display_path(path));
}

void write_png(const std::filesystem::path& path, const ImageFrame& image) {
  const std::string file = path.string();
  if (image.bit_depth != 8 || (image.channels != 1 && image.channels != 3) ||
      image.pixels.size() != static_cast<size_t>(image.width) * image.height * image.channels)
    throw IoError(file +
                  ": write_png expects 8-bit gray or RGB pixels of width*height*channels bytes");
  write_file_replacing(path,
                       encode_png(image.pixels.data(), image.width, image.height, image.channels));
}

ImageFolderReader::ImageFolderReader(const std::filesystem::path& folder)
    : entries_(read_folder_index(folder)) {}

bool ImageFolderReader::next(ImageFrame& frame, bool decode) {
  if (next_ >= entries_.size()) return false;
  const IndexEntry& entry = entries_[next_++];
  frame = decode ? read_png(entry.path) : read_png_info(entry.path);
  frame.t_ns = entry.t_ns;
  return true;
}

std::string ImageFolderReader::current_source() const {
  return next_ == 0 ? std::string() : display_path(entries_[next_ - 1].path);
}

}  // namespace keel::io
