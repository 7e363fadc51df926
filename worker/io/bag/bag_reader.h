// ROS1 bags as typed topics, read by Keel itself (ros1_bag.h: ROS bag format 2.0; messages
// decoded by ros1_messages.h), without any ROS library.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "worker/io/bag/bag_source.h"

namespace keel::io {

class BagReader : public BagSource {
 public:
  // Opens the bag and reads its index. A truncated or corrupt bag fails naming the bag.
  explicit BagReader(const std::filesystem::path& path);
  ~BagReader() override;

  const std::filesystem::path& path() const override;
  const std::vector<BagTopicInfo>& topics() const override;

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

  struct Impl;

 private:
  std::shared_ptr<Impl> impl_;  // shared with open sources, which may outlive the reader
};

}  // namespace keel::io
