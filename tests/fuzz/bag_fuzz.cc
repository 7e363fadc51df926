// ROS 1 bags (worker/io/bag/bag_reader.h on Keel's own reader, ros1_bag.h): any bytes open
// and read every topic as what its type says, or are refused naming the bag (and topic,
// message).
#include <stdexcept>

#include "tests/fuzz/fuzz_util.h"
#include "worker/io/bag/bag_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  namespace io = keel::io;
  const auto file = keel::fuzz::write_input("fuzz.bag", data, size);
  try {
    io::BagReader bag(file);
    for (const io::BagTopicInfo& topic : bag.topics()) {
      try {
        if (topic.datatype == "sensor_msgs/Imu")
          (void)bag.read_imu(topic.topic);
        else if (topic.datatype == "tf2_msgs/TFMessage")
          (void)bag.read_static_transforms(topic.topic);
        else if (topic.datatype == "sensor_msgs/PointCloud2") {
          auto scans = bag.open_scans(topic.topic, {});
          keel::PointCloud cloud;
          while (scans->next(cloud)) {
          }
        } else if (topic.datatype == "nav_msgs/Odometry" ||
                   topic.datatype == "geometry_msgs/PoseStamped")
          (void)bag.read_trajectory(topic.topic);
        else
          (void)bag.read_dvl(topic.topic);
      } catch (const std::runtime_error&) {
      }
    }
  } catch (const std::runtime_error&) {
  }
  return 0;
}
