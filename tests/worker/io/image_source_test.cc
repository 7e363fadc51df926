// Camera images: pixels written as PNG read back equal; JPEG decodes to its size; what is not
// a PNG or JPEG, empty or cut short is refused with an IoError naming the source, before any
// other codec OpenCV carries sees it (fuzz_image found GDCM's DICOM reader aborting).
#include "worker/io/image_source.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "tests/worker/io/image_test_util.h"
#include "worker/io/io_error.h"

namespace keel::io {
namespace {

using image_testing::encode;
std::string refusal(const std::vector<uint8_t>& bytes) {
  return image_testing::refusal(bytes, "cam0/000001.png");
}

TEST(ImageSource, PngPixelsReadBackEqualAndJpegDecodesToItsSize) {
  ImageFrame rgb;
  rgb.width = 5;
  rgb.height = 3;
  rgb.channels = 3;
  rgb.bit_depth = 8;
  for (int i = 0; i < 45; ++i) rgb.pixels.push_back(static_cast<uint8_t>(17 * i));
  const auto path = std::filesystem::temp_directory_path() / "keel_image_source_test.png";
  write_png(path, rgb);
  const ImageFrame back = read_png(path);
  EXPECT_EQ(back.width, 5);
  EXPECT_EQ(back.height, 3);
  EXPECT_EQ(back.channels, 3);
  EXPECT_EQ(back.pixels, rgb.pixels);  // RGB order kept through OpenCV's BGR
  std::filesystem::remove(path);

  const ImageFrame jpeg = decode_image(encode(".jpg", cv::Mat(6, 8, CV_8UC1, 90)), "a.jpg");
  EXPECT_EQ(jpeg.width, 8);
  EXPECT_EQ(jpeg.height, 6);
  EXPECT_EQ(jpeg.channels, 1);
}

TEST(ImageSource, OnlyPngAndJpegReachTheCodecs) {
  EXPECT_EQ(refusal({}), "cam0/000001.png: empty image (0 bytes)");
  const std::string not_png_or_jpeg = "cam0/000001.png: not a PNG or JPEG image";
  // A TIFF OpenCV would decode, and fuzz_image's input: a PNG signature with one byte changed
  // and "DICM" at offset 128, which sent imdecode to GDCM, whose reader aborts.
  EXPECT_NE(refusal(encode(".tiff", cv::Mat(4, 4, CV_8UC1, 7))).find(not_png_or_jpeg),
            std::string::npos);
  std::vector<uint8_t> dicom_like(135, 0);
  const uint8_t head[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0xa6, 0x1f};
  std::copy(head, head + 8, dicom_like.begin());
  const std::string dicm = "DICM";
  std::copy(dicm.begin(), dicm.end(), dicom_like.begin() + 128);
  EXPECT_NE(refusal(dicom_like).find(not_png_or_jpeg), std::string::npos) << refusal(dicom_like);
}

TEST(ImageSource, ACutShortPngOrJpegIsRefusedNamingTheSource) {
  for (const char* ext : {".png", ".jpg"}) {
    std::vector<uint8_t> bytes = encode(ext, cv::Mat(16, 16, CV_8UC3, cv::Scalar(1, 2, 3)));
    bytes.resize(bytes.size() / 3);
    const std::string message = refusal(bytes);
    EXPECT_EQ(message.rfind("cam0/000001.png: ", 0), 0u) << ext << ": " << message;
  }
}

}  // namespace
}  // namespace keel::io
