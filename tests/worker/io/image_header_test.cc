// Image kind and size read from the header equal what OpenCV encoded (PNG; baseline and
// progressive JPEG, with segments before the frame); a header cut short gives nothing; an
// image declaring more than kMaxImagePixels is refused before OpenCV allocates for it.
#include "worker/io/image_header.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "tests/worker/io/image_test_util.h"
#include "worker/io/image_source.h"
#include "worker/io/io_error.h"

namespace keel::io {
namespace {

using image_testing::encode;
std::string refusal(const std::vector<uint8_t>& bytes) {
  return image_testing::refusal(bytes, "cam0/000002.jpg");
}

std::optional<ImageSize> size_of(const std::vector<uint8_t>& bytes) {
  return read_image_size(bytes.data(), bytes.size());
}

// The offset of the first SOF0/SOF2 marker (FF C0 or FF C2) in an encoded JPEG.
size_t frame_marker(const std::vector<uint8_t>& jpeg) {
  for (size_t i = 2; i + 1 < jpeg.size(); ++i)
    if (jpeg[i] == 0xff && (jpeg[i + 1] == 0xc0 || jpeg[i + 1] == 0xc2)) return i;
  return 0;
}

TEST(ImageHeader, SizesAreTheOnesEncoded) {
  const cv::Mat color(23, 37, CV_8UC3, cv::Scalar(10, 20, 30));
  const cv::Mat gray(5, 300, CV_8UC1, cv::Scalar(7));
  for (const auto& bytes : {encode(".png", color), encode(".jpg", color), encode(".png", gray),
                            encode(".jpg", gray, {cv::IMWRITE_JPEG_PROGRESSIVE, 1})}) {
    const auto size = size_of(bytes);
    ASSERT_TRUE(size);
    const bool is_gray = size->width == 300;
    EXPECT_EQ(size->width, is_gray ? 300u : 37u);
    EXPECT_EQ(size->height, is_gray ? 5u : 23u);
  }
  EXPECT_EQ(image_kind(encode(".png", gray).data(), 8), ImageKind::kPng);
  EXPECT_EQ(image_kind(encode(".jpg", gray).data(), 3), ImageKind::kJpeg);
  const auto tiff = encode(".tiff", gray);
  EXPECT_FALSE(image_kind(tiff.data(), tiff.size()));
}

TEST(ImageHeader, JpegSegmentsBeforeTheFrameAndFillBytesAreWalked) {
  std::vector<uint8_t> jpeg = encode(".jpg", cv::Mat(9, 11, CV_8UC1, cv::Scalar(1)));
  // A comment (FF FE, length 6: "Keel") and two fill bytes after SOI.
  const std::vector<uint8_t> comment = {0xff, 0xff, 0xff, 0xfe, 0x00, 0x06, 'K', 'e', 'e', 'l'};
  jpeg.insert(jpeg.begin() + 2, comment.begin(), comment.end());
  const auto size = size_of(jpeg);
  ASSERT_TRUE(size);
  EXPECT_EQ(size->width, 11u);
  EXPECT_EQ(size->height, 9u);
}

TEST(ImageHeader, AHeaderCutShortOrMalformedGivesNothing) {
  const auto jpeg = encode(".jpg", cv::Mat(9, 11, CV_8UC1, cv::Scalar(1)));
  const size_t sof = frame_marker(jpeg);
  ASSERT_GT(sof, 2u);
  // Marker (2), length (2), precision (1), height (2), width (2): libjpeg reads no more first.
  for (size_t cut = 0; cut < sof + 9; ++cut)
    EXPECT_FALSE(read_image_size(jpeg.data(), cut)) << "cut at " << cut;
  EXPECT_TRUE(read_image_size(jpeg.data(), sof + 9));
  const auto png = encode(".png", cv::Mat(9, 11, CV_8UC1, cv::Scalar(1)));
  EXPECT_FALSE(read_image_size(png.data(), 23));
  EXPECT_TRUE(read_image_size(png.data(), 24));
}

TEST(ImageHeader, ASegmentLengthUnderTwoIsReadPastAsLibjpegDoes) {
  // fuzz_image's input: an APP0 of length 0, after which libjpeg reads the next marker.
  std::vector<uint8_t> jpeg = encode(".jpg", cv::Mat(9, 11, CV_8UC1, cv::Scalar(1)));
  const std::vector<uint8_t> app0 = {0xff, 0xe0, 0x00, 0x00};
  jpeg.insert(jpeg.begin() + 2, app0.begin(), app0.end());
  const auto size = size_of(jpeg);
  ASSERT_TRUE(size);
  EXPECT_EQ(size->width, 11u);
  EXPECT_EQ(size->height, 9u);
}

TEST(ImageHeader, AJpegWithoutAFrameHeaderBeforeItsDataIsRefused) {
  const std::vector<uint8_t> jpeg = {0xff, 0xd8, 0xff, 0xda, 0x00, 0x08, 1, 2, 3, 4, 5, 6};
  EXPECT_FALSE(size_of(jpeg));
  EXPECT_EQ(refusal(jpeg), "cam0/000002.jpg: JPEG without a frame header (SOF) before its data");
}

TEST(ImageHeader, BytesWhereAMarkerShouldBeAreSkippedAsLibjpegSkipsThem) {
  // fuzz_image's input: garbage between two segments, then a frame of 64520 x 12334 that
  // libjpeg reads after warning "extraneous bytes before marker".
  std::vector<uint8_t> jpeg = encode(".jpg", cv::Mat(9, 11, CV_8UC1, cv::Scalar(1)));
  const size_t sof = frame_marker(jpeg);
  const std::vector<uint8_t> garbage = {0x14, 0x15, 0x00};
  jpeg.insert(jpeg.begin() + sof, garbage.begin(), garbage.end());
  const auto size = size_of(jpeg);
  ASSERT_TRUE(size);
  EXPECT_EQ(size->width, 11u);
  EXPECT_EQ(size->height, 9u);
}

TEST(ImageHeader, AnImageDeclaringTooManyPixelsIsRefusedBeforeDecoding) {
  // 30000 x 30000 in a 1 KB JPEG: libjpeg would fill the missing rows, 2.7 GB each copy.
  std::vector<uint8_t> jpeg = encode(".jpg", cv::Mat(16, 16, CV_8UC3, cv::Scalar(1, 2, 3)));
  const size_t sof = frame_marker(jpeg);
  for (size_t at : {sof + 5, sof + 7}) {  // height, width: 30000 = 0x7530
    jpeg[at] = 0x75;
    jpeg[at + 1] = 0x30;
  }
  EXPECT_EQ(refusal(jpeg),
            "cam0/000002.jpg: image of 30000 x 30000 pixels, more than Keel reads (67108864)");
  std::vector<uint8_t> png = encode(".png", cv::Mat(16, 16, CV_8UC1, cv::Scalar(1)));
  png[18] = 0x40;  // width 0x4010 = 16400, height 16400: 2^28 pixels
  png[22] = 0x40;
  EXPECT_NE(refusal(png).find("16400 x 16400 pixels, more than Keel reads"), std::string::npos)
      << refusal(png);
}

}  // namespace
}  // namespace keel::io
