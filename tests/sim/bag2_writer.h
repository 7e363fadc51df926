// Writes simulated data as a ROS 2 bag: a rosbag2 folder with metadata.yaml and one or more
// split files, MCAP (mcap_writer.h) or SQLite3 (db3_writer.h), messages CDR-encoded with the
// ROS 2 layouts of the same types the ROS1 BagWriter writes. No ROS 2 install needed.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "tests/sim/bag_sink.h"
#include "worker/io/bag/a50_messages.h"

namespace keel::sim {

struct Bag2Options {
  std::string storage = "mcap";      // mcap | sqlite3
  std::string compression = "zstd";  // MCAP chunks: zstd | lz4 | none
  uint64_t max_file_bytes = 0;       // split into a new file beyond this size; 0 = one file
};

class Bag2Writer : public BagSink {
 public:
  Bag2Writer(const std::string& folder, Bag2Options options);  // throws naming the folder
  ~Bag2Writer() override;
  Bag2Writer(const Bag2Writer&) = delete;
  Bag2Writer& operator=(const Bag2Writer&) = delete;

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
  // Closes the last file and writes metadata.yaml.
  void transforms(const std::string& topic, TimeNs t_ns, const TransformEdges& edges) override;
  // A Water Linked A50 message (ROS1 waterlinked_a50_ros_driver/DVL, ROS 2 dvl_msgs/msg/DVL)
  // stamped m.stamp_ns; layouts as worker/io/bag/a50_messages.h describes.
  void a50_dvl(const std::string& topic, const std::string& frame, const io::A50Dvl& m);
  void close() override;

 private:
  struct File;
  void record(const std::string& topic, const std::string& type, TimeNs t_ns,
              const std::vector<uint8_t>& cdr);
  void open_file();
  void close_file();

  std::string folder_;
  Bag2Options options_;
  std::unique_ptr<File> file_;
  struct FileInfo {
    std::string name;
    TimeNs start_ns = 0, end_ns = 0;
    uint64_t messages = 0;
  };
  std::vector<FileInfo> files_;
  struct TopicInfo {
    std::string type;
    uint64_t messages = 0;
  };
  std::map<std::string, TopicInfo> topics_;
  bool closed_ = false;
};

}  // namespace keel::sim
