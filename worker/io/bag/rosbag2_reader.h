// ROS 2 bags without ROS 2: a rosbag2 folder (metadata.yaml and its split files, read in
// order as one bag) or a single .mcap or .db3 file. MCAP per its specification
// (mcap_reader.h), SQLite3 storage through SQLite (db3_reader.h), messages CDR-decoded for the
// types the ROS1 reader knows (ros2_messages.h), per-message zstd compression (rosbag2's
// compression_mode MESSAGE) undone. One message in memory at a time (one MCAP chunk), so
// a multi-GB bag reads in bounded memory.
//
// Messages of a topic come in recording order (file order, then MCAP file order or the .db3
// row order). Errors name the storage file as the user knows it (display_path), the topic
// and the message index within the topic: "bag/run_0.mcap: topic '/imu' message 17: ...".
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "worker/io/bag/bag_source.h"

namespace keel::io {

class Rosbag2Reader : public BagSource {
 public:
  // Opens the folder or file and reads each storage file's topics (MCAP summary or a scan of
  // a file without one; the .db3 topics table). Fails naming the file on a wrong magic, a
  // corrupt summary, an unknown storage or compression.
  explicit Rosbag2Reader(const std::filesystem::path& path);
  ~Rosbag2Reader() override;

  const std::filesystem::path& path() const override;
  const std::vector<BagTopicInfo>& topics() const override;
  // The storage files read, in order.
  std::vector<std::filesystem::path> files() const;

  ImuSeries read_imu(const std::string& topic) const override;
  DvlSeries read_dvl(const std::string& topic) const override;
  GnssSeries read_gnss(const std::string& topic) const override;
  Trajectory read_trajectory(const std::string& topic) const override;
  std::vector<StaticTransform> read_static_transforms(
      const std::string& topic = "/tf_static") const override;
  std::unique_ptr<ScanSource> open_scans(const std::string& topic,
                                         ScanReadOptions options) const override;
  std::unique_ptr<ImageSource> open_images(const std::string& topic) const override;
  void for_each_raw_message(
      const std::string& topic,
      const std::function<bool(const BagRawMessage&, size_t index)>& body) const override;

  // A topic's messages as stored (CDR bytes after any per-message decompression), whatever
  // their type: the container tests read rosbag2's own test bags (std_msgs/msg/String, ...).
  struct RawMessage {
    std::string_view type;
    TimeNs log_time_ns = 0;  // the recorder's receive time
    const uint8_t* data = nullptr;
    size_t size = 0;
  };
  void for_each_message(const std::string& topic,
                        const std::function<void(const RawMessage&, size_t index)>& body) const;

  struct Impl;

 protected:
  std::string damage() const override;

 private:
  std::shared_ptr<Impl> impl_;  // shared with open sources, which may outlive the reader
};

}  // namespace keel::io
