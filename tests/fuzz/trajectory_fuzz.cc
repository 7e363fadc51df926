// Trajectories: TUM files (worker/io/tum.h) and KITTI pose files (worker/main/
// trajectory_source.h). Any text is read or refused naming the file and line.
#include <stdexcept>

#include "tests/fuzz/fuzz_util.h"
#include "worker/io/tum.h"
#include "worker/main/trajectory_source.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto input = keel::fuzz::split_selector(data, size);
  const auto file = keel::fuzz::write_input("trajectory.txt", input.data, input.size);
  try {
    if (input.selector % 2 == 0)
      (void)keel::io::read_tum(file);
    else
      (void)keel::worker::read_kitti_poses(file);
  } catch (const std::runtime_error&) {
  }
  return 0;
}
