// Camera images (worker/io/image_source.h): a mission's PNG files and the CompressedImage
// messages of ROS bags (PNG or JPEG) decode into a frame or are refused with an error naming
// the source. The codecs are Debian's libpng and libjpeg through OpenCV, not instrumented:
// libFuzzer steers by Keel's side, from valid seeds.
#include <stdexcept>
#include <vector>

#include "worker/io/image_source.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    (void)keel::io::decode_image(std::vector<uint8_t>(data, data + size), "fuzz.png");
  } catch (const std::runtime_error&) {  // IoError names the source
  }
  return 0;
}
