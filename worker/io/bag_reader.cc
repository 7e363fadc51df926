#include "worker/io/bag_reader.h"

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TwistStamped.h>
#include <geometry_msgs/TwistWithCovarianceStamped.h>
#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>

#include <cmath>
#include <cstring>
#include <map>
#include <set>

#include "worker/io/io_error.h"

namespace keel::io {

namespace fs = std::filesystem;

struct BagReader::Impl {
  fs::path path;
  rosbag::Bag bag;
  std::vector<BagTopicInfo> topics;

  std::string name() const { return path.string(); }

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
  if (index > 0 && t_ns <= previous_ns)
    throw IoError(where(impl, topic, index) + ": " +
                  (t_ns == previous_ns ? "duplicate" : "decreasing") + " stamp " +
                  format_seconds(t_ns) + " (previous " + format_seconds(previous_ns) +
                  "); expected strictly increasing header stamps");
}

template <typename Vector>
Eigen::Vector3d finite3(const Vector& v, const std::string& what) {
  const Eigen::Vector3d out(v.x, v.y, v.z);
  if (!out.allFinite()) throw IoError(what + ": non-finite value");
  return out;
}

Pose3 pose_of(const geometry_msgs::Pose& p, const std::string& what) {
  const Eigen::Quaterniond q(p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z);
  if (!q.coeffs().allFinite() || std::abs(q.norm() - 1.0) > 1e-3)
    throw IoError(
        what + ": orientation is not a unit quaternion (|q| = " + std::to_string(q.norm()) + ")");
  return make_pose(q, finite3(p.position, what));
}

FieldType field_type(uint8_t datatype, const std::string& name, const std::string& what) {
  using F = sensor_msgs::PointField;
  switch (datatype) {
    case F::INT8:
      return FieldType::kInt8;
    case F::UINT8:
      return FieldType::kUint8;
    case F::INT16:
      return FieldType::kInt16;
    case F::UINT16:
      return FieldType::kUint16;
    case F::INT32:
      return FieldType::kInt32;
    case F::UINT32:
      return FieldType::kUint32;
    case F::FLOAT32:
      return FieldType::kFloat32;
    case F::FLOAT64:
      return FieldType::kFloat64;
  }
  throw IoError(what + ": field '" + name + "' has unknown datatype " + std::to_string(datatype));
}

class BagScanSource : public ScanSource {
 public:
  BagScanSource(std::shared_ptr<const BagReader::Impl> impl, std::string topic,
                ScanReadOptions options)
      : impl_(std::move(impl)), topic_(std::move(topic)), options_(std::move(options)) {
    impl_->expect_type(topic_, {"sensor_msgs/PointCloud2"});
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
      auto msg = it_->instantiate<sensor_msgs::PointCloud2>();
      if (!msg) throw IoError(what + ": not a sensor_msgs/PointCloud2");
      const TimeNs t_ns = stamp_of(msg->header.stamp, *it_);
      check_increasing(*impl_, topic_, index_, t_ns, previous_ns_);
      cloud = unpack(*msg, t_ns, what);
      previous_ns_ = t_ns;
      ++index_;
      ++it_;
      return true;
    });
  }

 private:
  PointCloud unpack(const sensor_msgs::PointCloud2& msg, TimeNs t_ns,
                    const std::string& what) const {
    if (msg.is_bigendian) throw IoError(what + ": big-endian point data is not supported");
    const size_t points = static_cast<size_t>(msg.width) * msg.height;
    const size_t row_bytes = static_cast<size_t>(msg.width) * msg.point_step;
    if (msg.row_step < row_bytes ||
        msg.data.size() < static_cast<size_t>(msg.row_step) * msg.height)
      throw IoError(what + ": data holds " + std::to_string(msg.data.size()) + " bytes; " +
                    std::to_string(msg.height) + " rows of " + std::to_string(msg.row_step) +
                    " needed");
    PackedCloudView view;
    view.num_points = points;
    view.point_step = msg.point_step;
    for (const auto& f : msg.fields) {
      const FieldType type = field_type(f.datatype, f.name, what);
      if (f.offset + field_size(type) > msg.point_step)
        throw IoError(what + ": field '" + f.name + "' lies outside the point record");
      view.fields.push_back({f.name, type, f.offset, std::max<size_t>(1, f.count)});
    }
    if (msg.row_step == row_bytes) {
      view.data = msg.data.data();
      return unpack_cloud(view, t_ns, options_, what);
    }
    std::vector<uint8_t> packed(points * msg.point_step);  // drop row padding
    for (size_t r = 0; r < msg.height; ++r)
      std::memcpy(packed.data() + r * row_bytes, msg.data.data() + r * msg.row_step, row_bytes);
    view.data = packed.data();
    return unpack_cloud(view, t_ns, options_, what);
  }

  std::shared_ptr<const BagReader::Impl> impl_;
  std::string topic_;
  ScanReadOptions options_;
  size_t count_ = 0;
  std::unique_ptr<rosbag::View> view_;
  rosbag::View::iterator it_;
  size_t index_ = 0;
  TimeNs previous_ns_ = 0;
};

ImageFrame raw_image(const sensor_msgs::Image& msg, bool decode, const std::string& what) {
  ImageFrame frame;
  frame.width = static_cast<int>(msg.width);
  frame.height = static_cast<int>(msg.height);
  int in_channels = 0;
  const std::string& e = msg.encoding;
  if (e == "mono8" || e == "8UC1")
    frame.channels = in_channels = 1, frame.bit_depth = 8;
  else if (e == "mono16" || e == "16UC1")
    frame.channels = in_channels = 1, frame.bit_depth = 16;
  else if (e == "rgb8" || e == "bgr8" || e == "8UC3")
    frame.channels = 3, in_channels = 3, frame.bit_depth = 8;
  else if (e == "rgba8" || e == "bgra8" || e == "8UC4")
    frame.channels = 3, in_channels = 4, frame.bit_depth = 8;
  else
    throw IoError(what + ": image encoding '" + e +
                  "' not supported (mono8, mono16, rgb8, bgr8, rgba8, bgra8)");
  const size_t pixel_bytes = in_channels * frame.bit_depth / 8;
  if (msg.step < msg.width * pixel_bytes ||
      msg.data.size() < static_cast<size_t>(msg.step) * msg.height)
    throw IoError(what + ": image data holds " + std::to_string(msg.data.size()) + " bytes; " +
                  std::to_string(msg.height) + " rows of " + std::to_string(msg.step) + " needed");
  if (!decode) return frame;
  const bool swap = e == "bgr8" || e == "bgra8";
  frame.pixels.resize(static_cast<size_t>(frame.width) * frame.height * frame.channels *
                      frame.bit_depth / 8);
  size_t out = 0;
  for (size_t r = 0; r < msg.height; ++r) {
    const uint8_t* row = msg.data.data() + r * msg.step;
    if (in_channels == frame.channels && !swap) {
      std::memcpy(frame.pixels.data() + out, row, msg.width * pixel_bytes);
      out += msg.width * pixel_bytes;
      continue;
    }
    for (size_t c = 0; c < msg.width; ++c) {
      const uint8_t* p = row + c * in_channels;
      frame.pixels[out++] = swap ? p[2] : p[0];
      frame.pixels[out++] = p[1];
      frame.pixels[out++] = swap ? p[0] : p[2];
    }
  }
  return frame;
}

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
        auto msg = it_->instantiate<sensor_msgs::CompressedImage>();
        t_ns = stamp_of(msg->header.stamp, *it_);
        frame = decode_image(msg->data, what);  // sizes need decoding for JPEG
        if (!decode) frame.pixels.clear();
      } else {
        auto msg = it_->instantiate<sensor_msgs::Image>();
        t_ns = stamp_of(msg->header.stamp, *it_);
        frame = raw_image(*msg, decode, what);
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
  if (!fs::is_regular_file(path, ec)) throw IoError(path.string() + ": bag not found");
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
    throw IoError(path.string() + ": cannot open bag (truncated or corrupt?): " + e.what());
  }
}

BagReader::~BagReader() = default;

const fs::path& BagReader::path() const { return impl_->path; }
const std::vector<BagTopicInfo>& BagReader::topics() const { return impl_->topics; }
const BagTopicInfo& BagReader::topic(const std::string& name) const { return impl_->topic(name); }

bool BagReader::has_topic(const std::string& name) const {
  for (const auto& t : impl_->topics)
    if (t.topic == name) return true;
  return false;
}

ImuSeries BagReader::read_imu(const std::string& topic) const {
  impl_->expect_type(topic, {"sensor_msgs/Imu"});
  ImuSeries out;
  out.reserve(impl_->topic(topic).messages);
  impl_->for_each(topic, [&](const rosbag::MessageInstance& m, size_t i) {
    auto msg = m.instantiate<sensor_msgs::Imu>();
    const std::string what = where(*impl_, topic, i);
    ImuSample s;
    s.t_ns = stamp_of(msg->header.stamp, m);
    check_increasing(*impl_, topic, i, s.t_ns, out.empty() ? 0 : out.back().t_ns);
    s.gyro_rad_s = finite3(msg->angular_velocity, what + " angular_velocity");
    s.accel_m_s2 = finite3(msg->linear_acceleration, what + " linear_acceleration");
    out.push_back(s);
  });
  return out;
}

DvlSeries BagReader::read_dvl(const std::string& topic) const {
  const std::string type = impl_->expect_type(
      topic, {"geometry_msgs/TwistWithCovarianceStamped", "geometry_msgs/TwistStamped"});
  const bool with_covariance = type == "geometry_msgs/TwistWithCovarianceStamped";
  DvlSeries out;
  impl_->for_each(topic, [&](const rosbag::MessageInstance& m, size_t i) {
    DvlSample s;
    const geometry_msgs::Vector3* linear = nullptr;
    geometry_msgs::TwistWithCovarianceStamped::ConstPtr a;
    geometry_msgs::TwistStamped::ConstPtr b;
    if (with_covariance) {
      a = m.instantiate<geometry_msgs::TwistWithCovarianceStamped>();
      s.t_ns = stamp_of(a->header.stamp, m);
      linear = &a->twist.twist.linear;
    } else {
      b = m.instantiate<geometry_msgs::TwistStamped>();
      s.t_ns = stamp_of(b->header.stamp, m);
      linear = &b->twist.linear;
    }
    check_increasing(*impl_, topic, i, s.t_ns, out.empty() ? 0 : out.back().t_ns);
    s.velocity_m_s = finite3(*linear, where(*impl_, topic, i) + " twist.linear");
    out.push_back(s);
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
      auto msg = m.instantiate<nav_msgs::Odometry>();
      pose.t_ns = stamp_of(msg->header.stamp, m);
      pose.T_world_body = pose_of(msg->pose.pose, what + " pose");
    } else {
      auto msg = m.instantiate<geometry_msgs::PoseStamped>();
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
    auto msg = m.instantiate<tf2_msgs::TFMessage>();
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

bool lookup_static_transform(const std::vector<StaticTransform>& transforms,
                             const std::string& target_frame, const std::string& source_frame,
                             Pose3& T_target_source) {
  // Path to the root from each frame (a TF tree: every child has one parent).
  auto chain_to_root = [&](const std::string& frame) {
    std::vector<std::pair<std::string, Pose3>> chain;  // (frame, T_root?_frame accumulated)
    Pose3 T_current_frame = Pose3::Identity();
    std::string current = frame;
    chain.emplace_back(current, T_current_frame);
    std::set<std::string> seen{current};
    while (true) {
      const StaticTransform* edge = nullptr;
      for (const auto& t : transforms)
        if (t.child_frame == current) edge = &t;
      if (!edge || seen.count(edge->parent_frame)) break;
      T_current_frame = edge->T_parent_child * T_current_frame;  // T_parent_frame
      current = edge->parent_frame;
      seen.insert(current);
      chain.emplace_back(current, T_current_frame);
    }
    return chain;  // chain[k] = (ancestor_k, T_ancestor_k_frame)
  };
  const auto source_chain = chain_to_root(source_frame);
  const auto target_chain = chain_to_root(target_frame);
  for (const auto& [ancestor, T_ancestor_source] : source_chain)
    for (const auto& [other, T_other_target] : target_chain)
      if (ancestor == other) {
        T_target_source = T_other_target.inverse() * T_ancestor_source;
        return true;
      }
  return false;
}

}  // namespace keel::io
