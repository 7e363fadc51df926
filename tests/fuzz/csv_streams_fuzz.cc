// The sensor CSV streams (worker/io/stream_csv.h) and loop closures: any text is read or
// refused naming the file, line and column.
#include <stdexcept>

#include "tests/fuzz/fuzz_util.h"
#include "worker/io/loop_closures.h"
#include "worker/io/stream_csv.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  namespace io = keel::io;
  const auto input = keel::fuzz::split_selector(data, size);
  const auto file = keel::fuzz::write_input("stream.csv", input.data, input.size);
  try {
    switch (input.selector % 6) {
      case 0:
        (void)io::read_imu_csv(file);
        break;
      case 1:
        (void)io::read_dvl_csv(file);
        break;
      case 2:
        (void)io::read_dvl_ranges_csv(file);
        break;
      case 3:
        (void)io::read_depth_csv(file);
        break;
      case 4:
        (void)io::read_servo_csv(file);
        break;
      default:
        (void)io::read_loop_closures(file);
        break;
    }
  } catch (const std::runtime_error&) {
  }
  return 0;
}
