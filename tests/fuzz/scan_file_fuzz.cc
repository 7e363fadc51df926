// Point cloud scans: PCD (ascii, binary, binary_compressed) and PLY clouds
// (worker/io/cloud/scan_file.h). Any bytes are read or refused naming the file.
#include <stdexcept>

#include "tests/fuzz/fuzz_util.h"
#include "worker/io/cloud/scan_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  namespace io = keel::io;
  const auto input = keel::fuzz::split_selector(data, size);
  const bool pcd = input.selector % 2 == 0;
  const auto file = keel::fuzz::write_input(pcd ? "scan.pcd" : "scan.ply", input.data, input.size);
  io::ScanReadOptions options;
  options.keep_non_finite = (input.selector & 2) != 0;
  try {
    (void)io::read_scan_info(file);
    (void)io::read_scan_file(file, 0, options);
  } catch (const std::runtime_error&) {
  }
  return 0;
}
