// What keel-sim records into a bag, whatever the bag's format: ROS1 (bag_writer.h) or ROS 2
// (bag2_writer.h). Messages of one topic come in time order.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include "core/point_cloud.h"
#include "core/pose.h"

namespace keel::sim {

class BagSink {
 public:
  virtual ~BagSink() = default;
  virtual void imu(const std::string& topic, const std::string& frame, TimeNs t_ns,
                   const Eigen::Vector3d& gyro, const Eigen::Vector3d& accel) = 0;
  // DVL velocity as TwistWithCovarianceStamped (linear part; covariance from sigma).
  virtual void twist(const std::string& topic, const std::string& frame, TimeNs t_ns,
                     const Eigen::Vector3d& velocity, double sigma) = 0;
  // PointCloud2 with the cloud's fields (x y z [intensity] [ring] [time]).
  virtual void cloud(const std::string& topic, const std::string& frame,
                     const PointCloud& cloud) = 0;
  virtual void image(const std::string& topic, const std::string& frame, TimeNs t_ns,
                     const cv::Mat& gray) = 0;  // Image, mono8
  virtual void pose(const std::string& topic, const std::string& frame,
                    const StampedPose& pose) = 0;
  virtual void odometry(const std::string& topic, const std::string& frame,
                        const std::string& child_frame, const StampedPose& pose) = 0;
  // tf2_msgs/TFMessage: one message of edges (parent frame, child frame, T_parent_child).
  using TransformEdges = std::vector<std::tuple<std::string, std::string, Pose3>>;
  virtual void transforms(const std::string& topic, TimeNs t_ns, const TransformEdges& edges) = 0;
  virtual void close() = 0;
};

// Several bags written from one simulation (a ROS1 bag and ROS 2 bags of the same data).
class BagSinks : public BagSink {
 public:
  void add(std::unique_ptr<BagSink> sink) { sinks_.push_back(std::move(sink)); }
  bool empty() const { return sinks_.empty(); }
  void imu(const std::string& topic, const std::string& frame, TimeNs t_ns,
           const Eigen::Vector3d& gyro, const Eigen::Vector3d& accel) override {
    for (auto& s : sinks_) s->imu(topic, frame, t_ns, gyro, accel);
  }
  void twist(const std::string& topic, const std::string& frame, TimeNs t_ns,
             const Eigen::Vector3d& velocity, double sigma) override {
    for (auto& s : sinks_) s->twist(topic, frame, t_ns, velocity, sigma);
  }
  void cloud(const std::string& topic, const std::string& frame, const PointCloud& cloud) override {
    for (auto& s : sinks_) s->cloud(topic, frame, cloud);
  }
  void image(const std::string& topic, const std::string& frame, TimeNs t_ns,
             const cv::Mat& gray) override {
    for (auto& s : sinks_) s->image(topic, frame, t_ns, gray);
  }
  void pose(const std::string& topic, const std::string& frame, const StampedPose& pose) override {
    for (auto& s : sinks_) s->pose(topic, frame, pose);
  }
  void odometry(const std::string& topic, const std::string& frame, const std::string& child_frame,
                const StampedPose& pose) override {
    for (auto& s : sinks_) s->odometry(topic, frame, child_frame, pose);
  }
  void transforms(const std::string& topic, TimeNs t_ns, const TransformEdges& edges) override {
    for (auto& s : sinks_) s->transforms(topic, t_ns, edges);
  }
  void close() override {
    for (auto& s : sinks_) s->close();
  }

 private:
  std::vector<std::unique_ptr<BagSink>> sinks_;
};

}  // namespace keel::sim
