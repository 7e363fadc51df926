#include "worker/io/image_source.h"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>

#include "worker/io/display_path.h"
#include "worker/io/image_header.h"
#include "worker/io/io_error.h"
#include "worker/io/text_lines.h"

namespace keel::io {

namespace {

ImageFrame from_mat(const cv::Mat& decoded, const std::string& source) {
  cv::Mat mat = decoded;
  if (mat.channels() == 4) cv::cvtColor(mat, mat, cv::COLOR_BGRA2BGR);
  if (mat.channels() == 3) cv::cvtColor(mat, mat, cv::COLOR_BGR2RGB);
  if (mat.channels() != 1 && mat.channels() != 3)
    throw IoError(source + ": " + std::to_string(mat.channels()) +
                  " channels; expected gray or RGB");
  if (mat.depth() != CV_8U && mat.depth() != CV_16U)
    throw IoError(source + ": unsupported pixel depth; expected 8 or 16 bit");
  ImageFrame frame;
  frame.width = mat.cols;
  frame.height = mat.rows;
  frame.channels = mat.channels();
  frame.bit_depth = mat.depth() == CV_8U ? 8 : 16;
  const size_t row_bytes = mat.cols * mat.elemSize();
  frame.pixels.resize(row_bytes * mat.rows);
  for (int r = 0; r < mat.rows; ++r)
    std::memcpy(frame.pixels.data() + r * row_bytes, mat.ptr(r), row_bytes);
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

// Keel reads PNG and JPEG. cv::imdecode tries every codec OpenCV was built with, by signature
// (Debian's: DICOM through GDCM, TIFF, OpenEXR, JPEG 2000, WebP...): fuzz_image found GDCM
// aborting the process on bytes with "DICM" at offset 128. With a PNG or JPEG signature first,
// imdecode picks libpng or libjpeg, which come before GDCM in its list. The size is checked
// before OpenCV allocates for it (image_header.h).
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
  const cv::Mat buffer(1, static_cast<int>(encoded.size()), CV_8U,
                       const_cast<uint8_t*>(encoded.data()));
  cv::Mat mat;
  try {  // OpenCV throws cv::Exception (not a runtime_error) for what it refuses outright
    mat = cv::imdecode(buffer, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    throw IoError(source + ": cannot decode image: " + e.err);
  }
  if (mat.empty()) throw IoError(source + ": cannot decode image (truncated or not PNG/JPEG)");
  return from_mat(mat, source);
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
  cv::Mat mat(image.height, image.width, image.channels == 1 ? CV_8UC1 : CV_8UC3,
              const_cast<uint8_t*>(image.pixels.data()));
  // `mat` wraps the caller's pixels: the BGR copy goes to a buffer of its own (converting in
  // place swapped the caller's red and blue).
  cv::Mat out;
  if (image.channels == 3)
    cv::cvtColor(mat, out, cv::COLOR_RGB2BGR);
  else
    out = mat;
  if (!cv::imwrite(file, out)) throw IoError(file + ": cannot write PNG");
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
