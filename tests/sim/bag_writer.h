// Writes simulated data as a ROS1 bag (rosbag_storage, no ROS runtime). ROS headers stay
// in bag_writer.cc. It stays on ROS1's own library, apart from Keel's reader
// (worker/io/bag/ros1_bag.h), so that the bags the tests read are not Keel's own writing.
#pragma once

#include <memory>
#include <string>

#include "tests/sim/bag_sink.h"
#include "worker/io/bag/a50_messages.h"

namespace keel::sim {

enum class BagCompression { kNone, kBz2, kLz4 };  // of the bag's chunks

class BagWriter : public BagSink {
 public:
  // Throws naming the path.
  explicit BagWriter(const std::string& path, BagCompression compression = BagCompression::kNone);
  ~BagWriter() override;
  BagWriter(const BagWriter&) = delete;
  BagWriter& operator=(const BagWriter&) = delete;

  void imu(const std::string& topic, const std::string& frame, TimeNs t_ns,
           const Eigen::Vector3d& gyro, const Eigen::Vector3d& accel) override;
  void twist(const std::string& topic, const std::string& frame, TimeNs t_ns,
             const Eigen::Vector3d& velocity, double sigma) override;
  void cloud(const std::string& topic, const std::string& frame, const PointCloud& cloud) override;
  void image(const std::string& topic, const std::string& frame, TimeNs t_ns,
             const cv::Mat& gray) override;
  void pose(const std::string& topic, const std::string& frame, const StampedPose& pose) override;
  void odometry(const std::string& topic, const std::string& frame, const std::string& child_frame,
                const StampedPose& pose) override;
  void transforms(const std::string& topic, TimeNs t_ns, const TransformEdges& edges) override;
  // A Water Linked A50 message (ROS1 waterlinked_a50_ros_driver/DVL, ROS 2 dvl_msgs/msg/DVL)
  // stamped m.stamp_ns; layouts as worker/io/bag/a50_messages.h describes.
  void a50_dvl(const std::string& topic, const std::string& frame, const io::A50Dvl& m);
  void close() override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace keel::sim
