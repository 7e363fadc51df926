// Writes simulated data as a ROS1 bag (rosbag_storage, no ROS runtime). ROS headers stay
// in bag_writer.cc.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <memory>
#include <string>

#include "worker/core/point_cloud.h"
#include "worker/core/pose.h"

namespace keel::sim {

class BagWriter {
 public:
  explicit BagWriter(const std::string& path);  // throws naming the path
  ~BagWriter();
  BagWriter(const BagWriter&) = delete;
  BagWriter& operator=(const BagWriter&) = delete;

  void imu(const std::string& topic, const std::string& frame, TimeNs t_ns,
           const Eigen::Vector3d& gyro, const Eigen::Vector3d& accel);
  // DVL velocity as geometry_msgs/TwistWithCovarianceStamped (linear part; covariance from sigma).
  void twist(const std::string& topic, const std::string& frame, TimeNs t_ns,
             const Eigen::Vector3d& velocity, double sigma);
  // sensor_msgs/PointCloud2 with the cloud's fields (x y z [intensity] [ring] [time]).
  void cloud(const std::string& topic, const std::string& frame, const PointCloud& cloud);
  // sensor_msgs/Image, mono8.
  void image(const std::string& topic, const std::string& frame, TimeNs t_ns, const cv::Mat& gray);
  void pose(const std::string& topic, const std::string& frame, const StampedPose& pose);
  void odometry(const std::string& topic, const std::string& frame, const std::string& child_frame,
                const StampedPose& pose);
  void close();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace keel::sim
