// The GNSS fix CSV (worker/io/gnss_csv.h): any text is read or refused naming the file, line
// and column.
#include <stdexcept>

#include "tests/fuzz/fuzz_util.h"
#include "worker/io/gnss_csv.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto file = keel::fuzz::write_input("gnss.csv", data, size);
  try {
    (void)keel::io::read_gnss_csv(file);
  } catch (const std::runtime_error&) {
  }
  return 0;
}
