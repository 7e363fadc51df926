// libFuzzer target: what `keel init` reads of any recorded message (worker/init/raw_messages.h)
// and the point-time recogniser on the clouds it finds. The first byte picks the type and the
// serialization (even: ROS1, odd: CDR), the rest is the message. Only IoError may come out.
#include <cstddef>
#include <cstdint>

#include "worker/init/point_time_guess.h"
#include "worker/init/raw_messages.h"
#include "worker/io/io_error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  static const char* kTypes[] = {"sensor_msgs/PointCloud2",     "sensor_msgs/Image",
                                 "sensor_msgs/CompressedImage", "nav_msgs/Odometry",
                                 "sensor_msgs/NavSatFix",       "velodyne_msgs/VelodyneScan"};
  const size_t pick = (data[0] >> 1) % (sizeof(kTypes) / sizeof(kTypes[0]));
  keel::io::BagRawMessage m;
  m.type = kTypes[pick];
  m.cdr = (data[0] & 1) != 0;
  m.data = data + 1;
  m.size = size - 1;
  try {
    keel::init::read_header(m, "fuzz");
    switch (pick) {
      case 0: {
        const auto cloud = keel::init::read_point_cloud2(m, "fuzz");
        keel::init::guess_point_time(cloud.view, 0, 0.1);
        break;
      }
      case 1:
      case 2:
        keel::init::read_image_info(m, "fuzz");
        break;
      case 3:
        keel::init::read_odometry_child_frame(m, "fuzz");
        break;
      case 4:
        keel::init::read_nav_sat_fix(m, "fuzz");
        break;
      case 5:
        keel::init::read_velodyne_factory(m, "fuzz");
        break;
    }
  } catch (const keel::io::IoError&) {
  }
  return 0;
}
