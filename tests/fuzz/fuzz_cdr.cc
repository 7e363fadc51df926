// libFuzzer target: the CDR decoders of every ROS 2 type Keel reads. The first byte picks the
// type, the rest is the message.
#include "tests/fuzz/fuzz_decode.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const size_t types = sizeof(keel::fuzz::kTypes) / sizeof(keel::fuzz::kTypes[0]);
  keel::fuzz::decode_as(keel::fuzz::kTypes[data[0] % types], data + 1, size - 1);
  return 0;
}
