// The Draco decoder path (worker/io/draco_codec.h) that reads maps and hulls back: any
// bytes decode or are refused with an error naming the buffer.
#include <stdexcept>
#include <string>

#include "tests/fuzz/fuzz_util.h"
#include "worker/io/draco_codec.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto input = keel::fuzz::split_selector(data, size);
  const std::string bytes(reinterpret_cast<const char*>(input.data), input.size);
  try {
    if (input.selector % 2 == 0)
      (void)keel::io::decode_draco_point_cloud(bytes, "fuzz.drc");
    else
      (void)keel::io::decode_draco_mesh(bytes, "fuzz.drc");
  } catch (const std::runtime_error&) {
  }
  return 0;
}
