#include "worker/io/bag/bag_reader.h"

#include <map>
#include <vector>

#include "worker/io/bag/a50_dvl_sample.h"
#include "worker/io/bag/bag_format_error.h"
#include "worker/io/bag/byte_source.h"
#include "worker/io/bag/nav_sat_fix.h"
#include "worker/io/bag/ros1_bag.h"
#include "worker/io/bag/ros1_messages.h"
#include "worker/io/bag/ros_messages.h"
#include "worker/io/display_path.h"
#include "worker/io/io_error.h"

namespace keel::io {

namespace fs = std::filesystem;

struct BagReader::Impl {
  fs::path path;
  std::unique_ptr<Ros1Bag> bag;
  std::vector<BagTopicInfo> topics;

  std::string name() const { return display_path(path); }

  const BagTopicInfo& topic(const std::string& topic_name) const {
    for (const auto& t : topics)
      if (t.topic == topic_name) return t;
    std::string known;
    for (const auto& t : topics)
      known += (known.empty() ? "" : ", ") + t.topic + " (" + t.datatype + ")";
    throw IoError(name() + ": no topic '" + topic_name +
                  "' in the bag (topics: " + (known.empty() ? "none" : known) + ")");
  }

  // Checks the topic's type against `accepted`; returns the type.
  std::string expect_type(const std::string& topic_name,
                          std::initializer_list<const char*> accepted) const {
    const BagTopicInfo& info = topic(topic_name);
    std::string list;
    for (const char* type : accepted) {
      if (info.datatype == type) return info.datatype;
      list += (list.empty() ? "" : " or ") + std::string(type);
    }
    throw IoError(name() + ": topic '" + topic_name + "' holds " + info.datatype + "; expected " +
                  list);
  }
};

namespace {

// Names a message for errors: "<bag>: topic '/imu' message 17".
std::string where(const BagReader::Impl& impl, const std::string& topic, size_t index) {
  return impl.name() + ": topic '" + topic + "' message " + std::to_string(index);
}

// The messages of one topic in time order, with errors that name the bag, the topic and the
// message index.
class TopicCursor {
 public:
  TopicCursor(std::shared_ptr<const BagReader::Impl> impl, std::string topic)
      : impl_(std::move(impl)), topic_(std::move(topic)), cursor_(impl_->bag->messages(topic_)) {}

  bool next(Ros1Message& message) {
    try {
      if (!cursor_.next(message)) return false;
    } catch (const BagFormatError& e) {
      throw IoError(where(*impl_, topic_, index_) +
                    ": cannot read (truncated or corrupt bag?): " + e.what());
    }
    ++index_;
    return true;
  }
  // Of the message last returned.
  size_t index() const { return index_ - 1; }
  std::string what() const { return where(*impl_, topic_, index()); }
  const std::string& topic() const { return topic_; }

 private:
  std::shared_ptr<const BagReader::Impl> impl_;
  std::string topic_;
  Ros1Bag::Cursor cursor_;
  size_t index_ = 0;  // messages returned so far
};

// Runs `body(message, index, what)` over every message of a topic, naming the message in
// decoding errors.
template <typename Body>
void for_each(const std::shared_ptr<BagReader::Impl>& impl, const std::string& topic, Body&& body) {
  TopicCursor cursor(impl, topic);
  Ros1Message m;
  while (cursor.next(m)) {
    const std::string what = cursor.what();
    try {
      body(m, cursor.index(), what);
    } catch (const BagFormatError& e) {
      throw IoError(what + ": " + e.what());
    }
  }
}

// The message's connection must declare the MD5 of the type it is decoded as (a message
// definition changed under the same name, or a corrupt connection record, would be read as
// what it is not).
void check_md5(const Ros1Message& m, const std::string& type, const std::string& what) {
  const std::string_view md5 = ros1::md5_of(type);
  if (m.connection->md5sum != md5)
    throw IoError(what + ": a " + m.connection->datatype + " message (MD5 " + m.connection->md5sum +
                  "), not a " + type + " (MD5 " + std::string(md5) + ")");
}

TimeNs stamp_of(TimeNs header_stamp_ns, const Ros1Message& m) {
  return header_stamp_ns == 0 ? m.time_ns : header_stamp_ns;
}

class BagScanSource : public ScanSource {
 public:
  BagScanSource(std::shared_ptr<const BagReader::Impl> impl, std::string topic,
                ScanReadOptions options)
      : cursor_(impl, topic), options_(std::move(options)) {
    packets_ = impl->expect_type(topic, {"sensor_msgs/PointCloud2", kVelodyneScanRos1}) ==
               kVelodyneScanRos1;
    check_packet_options(impl->name(), topic, packets_, options_);
    count_ = impl->topic(topic).messages;
  }
  size_t size() const override { return count_; }
  std::string current_source() const override { return returned_ ? cursor_.what() : ""; }

  bool next(PointCloud& cloud) override {
    Ros1Message m;
    if (!cursor_.next(m)) return false;
    returned_ = true;
    const std::string what = cursor_.what();
    if (packets_) {
      // One VelodyneScan at a time, decoded from its serialised bytes.
      cloud = decode_velodyne_message(m.data, m.size, false, m.time_ns, options_, what, scratch_);
    } else {
      check_md5(m, "sensor_msgs/PointCloud2", what);
      ros1::PointCloud2 msg;
      try {
        msg = ros1::decode_point_cloud2(m.data, m.size);
      } catch (const BagFormatError& e) {
        throw IoError(what + ": " + e.what());
      }
      cloud = unpack_point_cloud2(msg.view, stamp_of(msg.stamp_ns, m), options_, what);
    }
    check_increasing(what, cursor_.index(), cloud.t_ns, previous_ns_);
    previous_ns_ = cloud.t_ns;
    return true;
  }

 private:
  TopicCursor cursor_;
  ScanReadOptions options_;
  size_t count_ = 0;
  bool returned_ = false;
  TimeNs previous_ns_ = 0;
  bool packets_ = false;  // velodyne_msgs/VelodyneScan
  std::vector<lidar::VelodynePoint> scratch_;
};

class BagImageSource : public ImageSource {
 public:
  BagImageSource(std::shared_ptr<const BagReader::Impl> impl, std::string topic)
      : cursor_(impl, topic) {
    compressed_ = impl->expect_type(topic, {"sensor_msgs/Image", "sensor_msgs/CompressedImage"}) ==
                  "sensor_msgs/CompressedImage";
    count_ = impl->topic(topic).messages;
  }
  size_t size() const override { return count_; }
  std::string current_source() const override { return returned_ ? cursor_.what() : ""; }

  bool next(ImageFrame& frame, bool decode) override {
    Ros1Message m;
    if (!cursor_.next(m)) return false;
    returned_ = true;
    const std::string what = cursor_.what();
    TimeNs t_ns = 0;
    try {
      if (compressed_) {
        check_md5(m, "sensor_msgs/CompressedImage", what);
        const ros1::CompressedImage msg = ros1::decode_compressed_image(m.data, m.size);
        t_ns = stamp_of(msg.stamp_ns, m);
        // sizes need decoding for JPEG
        frame = decode_image(std::vector<uint8_t>(msg.data, msg.data + msg.size), what);
        if (!decode) frame.pixels.clear();
      } else {
        check_md5(m, "sensor_msgs/Image", what);
        const ros1::Image msg = ros1::decode_image(m.data, m.size);
        t_ns = stamp_of(msg.stamp_ns, m);
        frame = unpack_image(msg.view, decode, what);
      }
    } catch (const BagFormatError& e) {
      throw IoError(what + ": " + e.what());
    }
    check_increasing(what, cursor_.index(), t_ns, previous_ns_);
    frame.t_ns = previous_ns_ = t_ns;
    return true;
  }

 private:
  TopicCursor cursor_;
  bool compressed_ = false;
  size_t count_ = 0;
  bool returned_ = false;
  TimeNs previous_ns_ = 0;
};

}  // namespace

BagReader::BagReader(const fs::path& path) : impl_(std::make_shared<Impl>()) {
  impl_->path = path;
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw IoError(impl_->name() + ": bag not found");
  try {
    impl_->bag =
        std::make_unique<Ros1Bag>(std::make_shared<FileBytes>(path, impl_->name()), impl_->name());
  } catch (const BagFormatError& e) {
    throw IoError(e.what());
  }
  // One entry per topic, sorted by name; a topic recorded under several connections takes
  // the type of the last.
  std::map<std::string, BagTopicInfo> by_topic;
  for (const auto& [id, c] : impl_->bag->connections()) {
    BagTopicInfo& info = by_topic[c.topic];
    info.topic = c.topic;
    info.datatype = c.datatype;
  }
  for (auto& [name, info] : by_topic) {
    info.messages = impl_->bag->message_count(name);
    impl_->topics.push_back(info);
  }
}

BagReader::~BagReader() = default;

const fs::path& BagReader::path() const { return impl_->path; }
const std::vector<BagTopicInfo>& BagReader::topics() const { return impl_->topics; }

void BagReader::for_each_raw_message(
    const std::string& topic,
    const std::function<bool(const BagRawMessage&, size_t index)>& body) const {
  impl_->topic(topic);
  TopicCursor cursor(impl_, topic);
  Ros1Message m;
  while (cursor.next(m))
    if (!body({m.connection->datatype, m.time_ns, m.data, m.size, false}, cursor.index())) return;
}

ImuSeries BagReader::read_imu(const std::string& topic) const {
  impl_->expect_type(topic, {"sensor_msgs/Imu"});
  ImuSeries out;
  out.reserve(impl_->topic(topic).messages);
  for_each(impl_, topic, [&](const Ros1Message& m, size_t i, const std::string& what) {
    check_md5(m, "sensor_msgs/Imu", what);
    const ros1::Imu msg = ros1::decode_imu(m.data, m.size);
    ImuSample s;
    s.t_ns = stamp_of(msg.stamp_ns, m);
    check_increasing(what, i, s.t_ns, out.empty() ? 0 : out.back().t_ns);
    const auto& w = msg.angular_velocity;
    const auto& a = msg.linear_acceleration;
    s.gyro_rad_s = finite_vector(w.x(), w.y(), w.z(), what + " angular_velocity");
    s.accel_m_s2 = finite_vector(a.x(), a.y(), a.z(), what + " linear_acceleration");
    out.push_back(s);
  });
  return out;
}

DvlSeries BagReader::read_dvl(const std::string& topic) const {
  const std::string type =
      impl_->expect_type(topic, {"geometry_msgs/TwistWithCovarianceStamped",
                                 "geometry_msgs/TwistStamped", "waterlinked_a50_ros_driver/DVL"});
  DvlSeries out;
  if (type == "waterlinked_a50_ros_driver/DVL") {
    // No MD5 check: driver versions that append dead-reckoning fields keep the prefix read
    // here (a50_messages.h).
    for_each(impl_, topic, [&](const Ros1Message& m, size_t i, const std::string& what) {
      const A50Dvl message = decode_a50_ros1(m.data, m.size);
      const TimeNs t_ns = stamp_of(message.stamp_ns, m);
      check_increasing(what, i, t_ns, out.empty() ? 0 : out.back().t_ns);
      out.push_back(a50_dvl_sample(message, t_ns, what));
    });
    return out;
  }
  const bool with_covariance = type == "geometry_msgs/TwistWithCovarianceStamped";
  for_each(impl_, topic, [&](const Ros1Message& m, size_t i, const std::string& what) {
    check_md5(m, type, what);
    const ros1::Twist msg = with_covariance
                                ? ros1::decode_twist_with_covariance_stamped(m.data, m.size)
                                : ros1::decode_twist_stamped(m.data, m.size);
    DvlSample s;
    s.t_ns = stamp_of(msg.stamp_ns, m);
    check_increasing(what, i, s.t_ns, out.empty() ? 0 : out.back().t_ns);
    const auto& v = msg.linear;
    s.velocity_m_s = finite_vector(v.x(), v.y(), v.z(), what + " twist.linear");
    out.push_back(s);
  });
  return out;
}

GnssSeries BagReader::read_gnss(const std::string& topic) const {
  impl_->expect_type(topic, {"sensor_msgs/NavSatFix"});
  GnssSeries out;
  out.reserve(impl_->topic(topic).messages);
  for_each(impl_, topic, [&](const Ros1Message& m, size_t i, const std::string& what) {
    check_md5(m, "sensor_msgs/NavSatFix", what);
    const ros1::NavSatFix msg = ros1::decode_nav_sat_fix(m.data, m.size);
    NavSatFixValues fix;
    fix.status = msg.status;
    fix.latitude_deg = msg.latitude_deg;
    fix.longitude_deg = msg.longitude_deg;
    fix.altitude_m = msg.altitude_m;
    fix.position_covariance = msg.position_covariance;
    fix.position_covariance_type = msg.position_covariance_type;
    const TimeNs t_ns = stamp_of(msg.stamp_ns, m);
    check_increasing(what, i, t_ns, out.empty() ? 0 : out.back().t_ns);
    out.push_back(gnss_sample_of(fix, t_ns, what));
  });
  return out;
}

Trajectory BagReader::read_trajectory(const std::string& topic) const {
  const std::string type =
      impl_->expect_type(topic, {"geometry_msgs/PoseStamped", "nav_msgs/Odometry"});
  const bool odometry = type == "nav_msgs/Odometry";
  Trajectory out;
  for_each(impl_, topic, [&](const Ros1Message& m, size_t i, const std::string& what) {
    check_md5(m, type, what);
    const ros1::Pose msg = odometry ? ros1::decode_odometry(m.data, m.size)
                                    : ros1::decode_pose_stamped(m.data, m.size);
    StampedPose pose;
    pose.t_ns = stamp_of(msg.stamp_ns, m);
    check_increasing(what, i, pose.t_ns, out.empty() ? 0 : out.back().t_ns);
    pose.T_world_body = checked_pose(msg.orientation, msg.position, what + " pose");
    out.push_back(pose);
  });
  return out;
}

std::vector<StaticTransform> BagReader::read_static_transforms(const std::string& topic) const {
  std::vector<StaticTransform> out;
  if (!has_topic(topic)) return out;
  impl_->expect_type(topic, {"tf2_msgs/TFMessage"});
  for_each(impl_, topic, [&](const Ros1Message& m, size_t, const std::string& what) {
    check_md5(m, "tf2_msgs/TFMessage", what);
    for (const auto& t : ros1::decode_tf_message(m.data, m.size)) {
      StaticTransform edge{t.parent_frame, t.child_frame,
                           checked_pose(t.rotation, t.translation,
                                        what + " " + t.parent_frame + "->" + t.child_frame)};
      // Frame names in tf2 carry no leading '/'.
      for (std::string* f : {&edge.parent_frame, &edge.child_frame})
        if (!f->empty() && f->front() == '/') f->erase(0, 1);
      out.push_back(edge);
    }
  });
  return out;
}

std::unique_ptr<ScanSource> BagReader::open_scans(const std::string& topic,
                                                  ScanReadOptions options) const {
  return std::make_unique<BagScanSource>(impl_, topic, std::move(options));
}

std::unique_ptr<ImageSource> BagReader::open_images(const std::string& topic) const {
  return std::make_unique<BagImageSource>(impl_, topic);
}

}  // namespace keel::io
