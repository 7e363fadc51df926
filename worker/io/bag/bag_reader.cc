#include "worker/io/bag/bag_reader.h"

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TwistStamped.h>
#include <geometry_msgs/TwistWithCovarianceStamped.h>
#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/NavSatFix.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>

#include <boost/make_shared.hpp>
#include <map>
#include <vector>

#include "worker/io/bag/a50_dvl_sample.h"
#include "worker/io/bag/bag_format_error.h"
#include "worker/io/bag/bag_record_check.h"
#include "worker/io/bag/nav_sat_fix.h"
#include "worker/io/bag/ros1_message_check.h"
#include "worker/io/bag/ros_messages.h"
#include "worker/io/display_path.h"
#include "worker/io/io_error.h"

namespace keel::io {

namespace fs = std::filesystem;

struct BagReader::Impl {
  fs::path path;
  rosbag::Bag bag;
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

  // Runs `body` over every message of a topic, turning rosbag errors into IoError.
  template <typename Body>
  void for_each(const std::string& topic_name, Body&& body) const {
    try {
      rosbag::View view(bag, rosbag::TopicQuery(topic_name));
      size_t index = 0;
      for (const rosbag::MessageInstance& m : view) body(m, index++);
    } catch (const rosbag::BagException& e) {
      throw IoError(name() + ": cannot read topic '" + topic_name +
                    "' (truncated or corrupt bag?): " + e.what());
    } catch (const ros::Exception& e) {
      throw IoError(name() + ": cannot decode a message of topic '" + topic_name +
                    "': " + e.what());
    }
  }
};

namespace {

TimeNs stamp_of(const ros::Time& header_stamp, const rosbag::MessageInstance& m) {
  const ros::Time t = header_stamp.isZero() ? m.getTime() : header_stamp;
  return static_cast<TimeNs>(t.sec) * 1000000000 + t.nsec;
}

// Decodes a message as T. rosbag's MessageInstance::instantiate would give a null message
// when the message's connection declares another MD5 than T's (a topic written under two
// types, or a corrupt connection record: fuzz_bag found it dereferenced), and roscpp's
// deserializer allocates each array's declared length before it looks whether the message
// holds it (4 GiB for a PointCloud2 in fuzz_bag); both are checked first, naming the message.
template <typename T>
boost::shared_ptr<T> instantiate_as(const rosbag::MessageInstance& m, const std::string& what) {
  const std::string md5 = ros::message_traits::md5sum<T>();
  if (m.getMD5Sum() != md5)
    throw IoError(what + ": a " + m.getDataType() + " message (MD5 " + m.getMD5Sum() + "), not a " +
                  ros::message_traits::datatype<T>() + " (MD5 " + md5 + ")");
  std::vector<uint8_t> bytes(m.size());
  ros::serialization::OStream out(bytes.data(), static_cast<uint32_t>(bytes.size()));
  m.write(out);
  check_ros1_message(ros::message_traits::datatype<T>(), bytes.data(), bytes.size(), what);
  auto msg = boost::make_shared<T>();
  ros::serialization::IStream in(bytes.data(), static_cast<uint32_t>(bytes.size()));
  ros::serialization::deserialize(in, *msg);
  return msg;
}

// Names a message for errors: "<bag>: topic '/imu' message 17".
std::string where(const BagReader::Impl& impl, const std::string& topic, size_t index) {
  return impl.name() + ": topic '" + topic + "' message " + std::to_string(index);
}

// Reads one message with `read` (returns whether there was one), turning rosbag errors
// into an IoError that names the message.
template <typename Read>
bool read_guarded(const BagReader::Impl& impl, const std::string& topic, size_t index,
                  Read&& read) {
  try {
    return read();
  } catch (const rosbag::BagException& e) {
    throw IoError(where(impl, topic, index) +
                  ": cannot read (truncated or corrupt bag?): " + e.what());
  } catch (const ros::Exception& e) {
    throw IoError(where(impl, topic, index) + ": cannot decode: " + e.what());
  }
}

void check_increasing(const BagReader::Impl& impl, const std::string& topic, size_t index,
                      TimeNs t_ns, TimeNs previous_ns) {
  io::check_increasing(where(impl, topic, index), index, t_ns, previous_ns);
}

template <typename Vector>
Eigen::Vector3d finite3(const Vector& v, const std::string& what) {
  return finite_vector(v.x, v.y, v.z, what);
}

Pose3 pose_of(const geometry_msgs::Pose& p, const std::string& what) {
  const Eigen::Quaterniond q(p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z);
  return checked_pose(q, finite3(p.position, what), what);
}

PointCloud2View view_of(const sensor_msgs::PointCloud2& msg) {
  PointCloud2View view;
  view.height = msg.height;
  view.width = msg.width;
  for (const auto& f : msg.fields) view.fields.push_back({f.name, f.offset, f.datatype, f.count});
  view.is_bigendian = msg.is_bigendian;
  view.point_step = msg.point_step;
  view.row_step = msg.row_step;
  view.data = msg.data.data();
  view.data_size = msg.data.size();
  return view;
}

ImageView view_of(const sensor_msgs::Image& msg) {
  return {msg.height, msg.width, msg.encoding, msg.step, msg.data.data(), msg.data.size()};
}

class BagScanSource : public ScanSource {
 public:
  BagScanSource(std::shared_ptr<const BagReader::Impl> impl, std::string topic,
                ScanReadOptions options)
      : impl_(std::move(impl)), topic_(std::move(topic)), options_(std::move(options)) {
    packets_ = impl_->expect_type(topic_, {"sensor_msgs/PointCloud2", kVelodyneScanRos1}) ==
               kVelodyneScanRos1;
    check_packet_options(impl_->name(), topic_, packets_, options_);
    count_ = impl_->topic(topic_).messages;
    try {
      view_ = std::make_unique<rosbag::View>(impl_->bag, rosbag::TopicQuery(topic_));
      it_ = view_->begin();
    } catch (const rosbag::BagException& e) {
      throw IoError(impl_->name() + ": cannot read topic '" + topic_ + "': " + e.what());
    }
  }
  size_t size() const override { return count_; }
  std::string current_source() const override {
    return index_ == 0 ? "" : where(*impl_, topic_, index_ - 1);
  }

  bool next(PointCloud& cloud) override {
    return read_guarded(*impl_, topic_, index_, [&] {
      if (it_ == view_->end()) return false;
      const std::string what = where(*impl_, topic_, index_);
      if (packets_) {
        // One VelodyneScan at a time, decoded from its serialised bytes.
        bytes_.resize(it_->size());
        ros::serialization::OStream out(bytes_.data(), static_cast<uint32_t>(bytes_.size()));
        it_->write(out);
        const ros::Time received = it_->getTime();
        cloud = decode_velodyne_message(bytes_.data(), bytes_.size(), false,
                                        static_cast<TimeNs>(received.sec) * 1000000000 +
                                            received.nsec,
                                        options_, what, scratch_);
      } else {
        auto msg = instantiate_as<sensor_msgs::PointCloud2>(*it_, what);
        cloud = unpack_point_cloud2(view_of(*msg), stamp_of(msg->header.stamp, *it_), options_,
                                    what);
      }
      check_increasing(*impl_, topic_, index_, cloud.t_ns, previous_ns_);
      previous_ns_ = cloud.t_ns;
      ++index_;
      ++it_;
      return true;
    });
  }

 private:
  std::shared_ptr<const BagReader::Impl> impl_;
  std::string topic_;
  ScanReadOptions options_;
  size_t count_ = 0;
  std::unique_ptr<rosbag::View> view_;
  rosbag::View::iterator it_;
  size_t index_ = 0;
  TimeNs previous_ns_ = 0;
  bool packets_ = false;  // velodyne_msgs/VelodyneScan
  std::vector<uint8_t> bytes_;
  std::vector<lidar::VelodynePoint> scratch_;
};

class BagImageSource : public ImageSource {
 public:
  BagImageSource(std::shared_ptr<const BagReader::Impl> impl, std::string topic)
      : impl_(std::move(impl)), topic_(std::move(topic)) {
    compressed_ =
        impl_->expect_type(topic_, {"sensor_msgs/Image", "sensor_msgs/CompressedImage"}) ==
        "sensor_msgs/CompressedImage";
    count_ = impl_->topic(topic_).messages;
    view_ = std::make_unique<rosbag::View>(impl_->bag, rosbag::TopicQuery(topic_));
    it_ = view_->begin();
  }
  size_t size() const override { return count_; }
  std::string current_source() const override {
    return index_ == 0 ? "" : where(*impl_, topic_, index_ - 1);
  }

  bool next(ImageFrame& frame, bool decode) override {
    return read_guarded(*impl_, topic_, index_, [&] {
      if (it_ == view_->end()) return false;
      const std::string what = where(*impl_, topic_, index_);
      TimeNs t_ns = 0;
      if (compressed_) {
        auto msg = instantiate_as<sensor_msgs::CompressedImage>(*it_, what);
        t_ns = stamp_of(msg->header.stamp, *it_);
        frame = decode_image(msg->data, what);  // sizes need decoding for JPEG
        if (!decode) frame.pixels.clear();
      } else {
        auto msg = instantiate_as<sensor_msgs::Image>(*it_, what);
        t_ns = stamp_of(msg->header.stamp, *it_);
        frame = unpack_image(view_of(*msg), decode, what);
      }
      check_increasing(*impl_, topic_, index_, t_ns, previous_ns_);
      frame.t_ns = previous_ns_ = t_ns;
      ++index_;
      ++it_;
      return true;
    });
  }

 private:
  std::shared_ptr<const BagReader::Impl> impl_;
  std::string topic_;
  bool compressed_ = false;
  size_t count_ = 0;
  std::unique_ptr<rosbag::View> view_;
  rosbag::View::iterator it_;
  size_t index_ = 0;
  TimeNs previous_ns_ = 0;
};

}  // namespace

BagReader::BagReader(const fs::path& path) : impl_(std::make_shared<Impl>()) {
  impl_->path = path;
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw IoError(impl_->name() + ": bag not found");
  check_bag_records(path);  // rosbag trusts the lengths in record headers
  try {
    impl_->bag.open(path.string(), rosbag::bagmode::Read);
    rosbag::View all(impl_->bag);
    std::map<std::string, BagTopicInfo> by_topic;
    for (const rosbag::ConnectionInfo* c : all.getConnections()) {
      auto& info = by_topic[c->topic];
      info.topic = c->topic;
      info.datatype = c->datatype;
    }
    for (auto& [name, info] : by_topic) {
      info.messages = rosbag::View(impl_->bag, rosbag::TopicQuery(name)).size();
      impl_->topics.push_back(info);
    }
  } catch (const rosbag::BagException& e) {
    throw IoError(impl_->name() + ": cannot open bag (truncated or corrupt?): " + e.what());
  }
}

BagReader::~BagReader() = default;

const fs::path& BagReader::path() const { return impl_->path; }
const std::vector<BagTopicInfo>& BagReader::topics() const { return impl_->topics; }

void BagReader::for_each_raw_message(
    const std::string& topic,
    const std::function<bool(const BagRawMessage&, size_t index)>& body) const {
  impl_->topic(topic);
  std::vector<uint8_t> bytes;
  struct Stop {};  // leaves rosbag's view early
  try {
    impl_->for_each(topic, [&](const rosbag::MessageInstance& m, size_t i) {
      bytes.resize(m.size());
      ros::serialization::OStream out(bytes.data(), static_cast<uint32_t>(bytes.size()));
      m.write(out);
      const ros::Time t = m.getTime();
      if (!body({m.getDataType(), static_cast<TimeNs>(t.sec) * 1000000000 + t.nsec, bytes.data(),
                 bytes.size(), false},
                i))
        throw Stop{};
    });
  } catch (const Stop&) {
  }
}

ImuSeries BagReader::read_imu(const std::string& topic) const {
  impl_->expect_type(topic, {"sensor_msgs/Imu"});
  ImuSeries out;
  out.reserve(impl_->topic(topic).messages);
  impl_->for_each(topic, [&](const rosbag::MessageInstance& m, size_t i) {
    const std::string what = where(*impl_, topic, i);
    auto msg = instantiate_as<sensor_msgs::Imu>(m, what);
    ImuSample s;
    s.t_ns = stamp_of(msg->header.stamp, m);
    check_increasing(*impl_, topic, i, s.t_ns, out.empty() ? 0 : out.back().t_ns);
    s.gyro_rad_s = finite3(msg->angular_velocity, what + " angular_velocity");
    s.accel_m_s2 = finite3(msg->linear_acceleration, what + " linear_acceleration");
    out.push_back(s);
  });
  return out;
}

namespace {

// No message package of the A50 driver is installed: its messages are decoded from their
// bytes (a50_messages.h), whatever MD5 the connection declares (driver versions that append
// dead-reckoning fields keep the prefix read here).
DvlSeries read_a50(const BagReader::Impl& impl, const std::string& topic) {
  DvlSeries out;
  impl.for_each(topic, [&](const rosbag::MessageInstance& m, size_t i) {
    const std::string what = where(impl, topic, i);
    std::vector<uint8_t> bytes(m.size());
    ros::serialization::OStream stream(bytes.data(), static_cast<uint32_t>(bytes.size()));
    m.write(stream);
    A50Dvl message;
    try {
      message = decode_a50_ros1(bytes.data(), bytes.size());
    } catch (const BagFormatError& e) {
      throw IoError(what + ": " + e.what());
    }
    const TimeNs t_ns =
        message.stamp_ns != 0 ? message.stamp_ns : static_cast<TimeNs>(m.getTime().toNSec());
    check_increasing(impl, topic, i, t_ns, out.empty() ? 0 : out.back().t_ns);
    out.push_back(a50_dvl_sample(message, t_ns, what));
  });
  return out;
}

}  // namespace

DvlSeries BagReader::read_dvl(const std::string& topic) const {
  const std::string type =
      impl_->expect_type(topic, {"geometry_msgs/TwistWithCovarianceStamped",
                                 "geometry_msgs/TwistStamped", "waterlinked_a50_ros_driver/DVL"});
  if (type == "waterlinked_a50_ros_driver/DVL") return read_a50(*impl_, topic);
  const bool with_covariance = type == "geometry_msgs/TwistWithCovarianceStamped";
  DvlSeries out;
  impl_->for_each(topic, [&](const rosbag::MessageInstance& m, size_t i) {
    DvlSample s;
    const geometry_msgs::Vector3* linear = nullptr;
    geometry_msgs::TwistWithCovarianceStamped::ConstPtr a;
    geometry_msgs::TwistStamped::ConstPtr b;
    const std::string what = where(*impl_, topic, i);
    if (with_covariance) {
      a = instantiate_as<geometry_msgs::TwistWithCovarianceStamped>(m, what);
      s.t_ns = stamp_of(a->header.stamp, m);
      linear = &a->twist.twist.linear;
    } else {
      b = instantiate_as<geometry_msgs::TwistStamped>(m, what);
      s.t_ns = stamp_of(b->header.stamp, m);
      linear = &b->twist.linear;
    }
    check_increasing(*impl_, topic, i, s.t_ns, out.empty() ? 0 : out.back().t_ns);
    s.velocity_m_s = finite3(*linear, what + " twist.linear");
    out.push_back(s);
  });
  return out;
}

GnssSeries BagReader::read_gnss(const std::string& topic) const {
  impl_->expect_type(topic, {"sensor_msgs/NavSatFix"});
  GnssSeries out;
  out.reserve(impl_->topic(topic).messages);
  impl_->for_each(topic, [&](const rosbag::MessageInstance& m, size_t i) {
    const std::string what = where(*impl_, topic, i);
    auto msg = instantiate_as<sensor_msgs::NavSatFix>(m, what);
    NavSatFixValues fix;
    fix.status = msg->status.status;
    fix.latitude_deg = msg->latitude;
    fix.longitude_deg = msg->longitude;
    fix.altitude_m = msg->altitude;
    for (size_t k = 0; k < 9; ++k) fix.position_covariance[k] = msg->position_covariance[k];
    fix.position_covariance_type = msg->position_covariance_type;
    const TimeNs t_ns = stamp_of(msg->header.stamp, m);
    check_increasing(*impl_, topic, i, t_ns, out.empty() ? 0 : out.back().t_ns);
    out.push_back(gnss_sample_of(fix, t_ns, what));
  });
  return out;
}

Trajectory BagReader::read_trajectory(const std::string& topic) const {
  const std::string type =
      impl_->expect_type(topic, {"geometry_msgs/PoseStamped", "nav_msgs/Odometry"});
  const bool odometry = type == "nav_msgs/Odometry";
  Trajectory out;
  impl_->for_each(topic, [&](const rosbag::MessageInstance& m, size_t i) {
    const std::string what = where(*impl_, topic, i);
    StampedPose pose;
    if (odometry) {
      auto msg = instantiate_as<nav_msgs::Odometry>(m, what);
      pose.t_ns = stamp_of(msg->header.stamp, m);
      pose.T_world_body = pose_of(msg->pose.pose, what + " pose");
    } else {
      auto msg = instantiate_as<geometry_msgs::PoseStamped>(m, what);
      pose.t_ns = stamp_of(msg->header.stamp, m);
      pose.T_world_body = pose_of(msg->pose, what + " pose");
    }
    check_increasing(*impl_, topic, i, pose.t_ns, out.empty() ? 0 : out.back().t_ns);
    out.push_back(pose);
  });
  return out;
}

std::vector<StaticTransform> BagReader::read_static_transforms(const std::string& topic) const {
  std::vector<StaticTransform> out;
  if (!has_topic(topic)) return out;
  impl_->expect_type(topic, {"tf2_msgs/TFMessage"});
  impl_->for_each(topic, [&](const rosbag::MessageInstance& m, size_t i) {
    auto msg = instantiate_as<tf2_msgs::TFMessage>(m, where(*impl_, topic, i));
    for (const auto& t : msg->transforms) {
      const std::string what =
          where(*impl_, topic, i) + " " + t.header.frame_id + "->" + t.child_frame_id;
      geometry_msgs::Pose p;
      p.position.x = t.transform.translation.x;
      p.position.y = t.transform.translation.y;
      p.position.z = t.transform.translation.z;
      p.orientation = t.transform.rotation;
      StaticTransform edge{t.header.frame_id, t.child_frame_id, pose_of(p, what)};
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
