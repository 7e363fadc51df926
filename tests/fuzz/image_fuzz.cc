// Camera images (worker/io/image_source.h): a mission's PNG files and the CompressedImage
// messages of ROS bags (PNG or JPEG) decode into a frame or are refused with an error naming
// the source. The codecs are Debian's libpng and libjpeg through OpenCV, not instrumented:
// libFuzzer steers by Keel's side, from valid seeds.
#include <stdexcept>
#include <vector>

#include "worker/io/image_source.h"

// Keel's limit (2^26 pixels) is for a worker with gigabytes to spare: at 8 bytes a pixel (RGBA,
// 16 bits) and three copies it is 1.5 GB, over libFuzzer's 2 GB with its own.
constexpr uint64_t kMaxPixels = 1 << 22;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    (void)keel::io::decode_image(std::vector<uint8_t>(data, data + size), "fuzz.png", kMaxPixels);
  } catch (const std::runtime_error&) {  // IoError names the source
  }
  return 0;
}
