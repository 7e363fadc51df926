// The sensor CSV streams (worker/io/stream_csv.h) and loop closures: any text is read or
// refused naming the file, line and column.
#include <stdexcept>

#include "tests/fuzz/csv_streams.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto input = keel::fuzz::split_selector(data, size);
  const auto file = keel::fuzz::write_input("stream.csv", input.data, input.size);
  try {
    keel::fuzz::read_csv_stream(input.selector, file);
  } catch (const std::runtime_error&) {
  }
  return 0;
}
