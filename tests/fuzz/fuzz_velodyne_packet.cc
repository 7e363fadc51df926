// Raw Velodyne packets (worker/io/lidar/): a data packet decoded with each model's table and
// either azimuth option, a VelodyneScan message (ROS 1 or CDR) parsed and decoded, and a
// driver calibration YAML. The first byte picks the case; bad input may only end in IoError.
#include <string>
#include <vector>

#include "worker/io/io_error.h"
#include "worker/io/lidar/velodyne_scan.h"

namespace {

using namespace keel::io::lidar;

VelodyneModel model_of(uint8_t selector) {
  switch (selector % 3) {
    case 0:
      return VelodyneModel::kVlp16;
    case 1:
      return VelodyneModel::kVlp32c;
    default:
      return VelodyneModel::kHdl32e;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const uint8_t selector = data[0];
  ++data, --size;
  static const VelodyneCalibration calibrations[3] = {factory_calibration(VelodyneModel::kVlp16),
                                                      factory_calibration(VelodyneModel::kVlp32c),
                                                      factory_calibration(VelodyneModel::kHdl32e)};
  const VelodyneCalibration& calibration = calibrations[(selector >> 2) % 3];
  VelodyneDecodeOptions options;
  options.interpolate_azimuth = (selector & 16) == 0;
  options.round_azimuth_to_centidegree = (selector & 32) != 0;
  options.keep_duplicate_returns = (selector & 64) != 0;
  std::vector<VelodynePoint> points;
  try {
    switch (selector % 4) {
      case 0:
        decode_velodyne_packet(data, size, calibration, options, points);
        break;
      case 1:
      case 2: {
        const VelodyneScanView scan = selector % 4 == 1 ? parse_velodyne_scan_ros1(data, size)
                                                        : parse_velodyne_scan_cdr(data, size);
        (void)decode_velodyne_scan(scan, 0, calibration, options, "fuzz", points);
        break;
      }
      default:
        (void)parse_velodyne_calibration(std::string(reinterpret_cast<const char*>(data), size),
                                         model_of(selector >> 2), "fuzz.yaml");
    }
  } catch (const keel::io::IoError&) {
  }
  return 0;
}
