// The Draco decoder path (worker/io/draco/draco_codec.h) that reads maps and hulls back: any
// bytes decode or are refused with an error naming the buffer. Seeds: fuzz_seeds' valid files.
#include <stdexcept>
#include <string>

#include "tests/fuzz/fuzz_util.h"
#include "worker/io/draco/draco_codec.h"

// Keel's limits are for a worker with gigabytes to spare; libFuzzer stops at 2 GB, and one
// Draco attribute may ask 2 KB a point (255 components of 8 bytes).
constexpr keel::io::DracoLimits kLimits{1 << 16, 1 << 18};

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto input = keel::fuzz::split_selector(data, size);
  const std::string bytes(reinterpret_cast<const char*>(input.data), input.size);
  try {
    if (input.selector % 2 == 0)
      (void)keel::io::decode_draco_point_cloud(bytes, "fuzz.drc", kLimits);
    else
      (void)keel::io::decode_draco_mesh(bytes, "fuzz.drc", kLimits);
  } catch (const std::runtime_error&) {
  }
  return 0;
}
