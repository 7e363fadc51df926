// Water Linked A50 DVL messages (worker/io/bag/a50_messages.h, a50_dvl_sample.h): the first
// byte picks the layout (even: ROS1 waterlinked_a50_ros_driver/DVL, odd: ROS 2 CDR
// dvl_msgs/msg/DVL), the rest is the message. Any bytes decode and give a sample, or are
// refused with BagFormatError (the bytes) or IoError (a value: non-finite, a bad beam id).
#include "worker/io/bag/a50_dvl_sample.h"
#include "worker/io/bag/a50_messages.h"
#include "worker/io/bag/bag_format_error.h"
#include "worker/io/io_error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  namespace io = keel::io;
  if (size == 0) return 0;
  try {
    const io::A50Dvl m = data[0] % 2 == 0 ? io::decode_a50_ros1(data + 1, size - 1)
                                          : io::decode_a50_ros2(data + 1, size - 1);
    const io::DvlSample s = io::a50_dvl_sample(m, m.stamp_ns, "fuzz");
    if (s.valid && !s.velocity_m_s.allFinite()) __builtin_trap();  // a valid sample is finite
  } catch (const io::BagFormatError&) {
  } catch (const io::IoError&) {
  }
  return 0;
}
