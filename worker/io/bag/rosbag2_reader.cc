#include "worker/io/bag/rosbag2_reader.h"

#include <zstd.h>

#include <map>
#include <optional>
#include <set>

#include "worker/io/bag/a50_dvl_sample.h"
#include "worker/io/bag/bag_format_error.h"
#include "worker/io/bag/byte_source.h"
#include "worker/io/bag/db3_reader.h"
#include "worker/io/bag/mcap_reader.h"
#include "worker/io/bag/nav_sat_fix.h"
#include "worker/io/bag/ros2_messages.h"
#include "worker/io/bag/ros_messages.h"
#include "worker/io/bag/rosbag2_metadata.h"
#include "worker/io/display_path.h"
#include "worker/io/io_error.h"

namespace keel::io {

namespace fs = std::filesystem;

namespace {

// A message larger than this after per-message decompression is refused before allocating.
constexpr uint64_t kMaxMessageBytes = 1ull << 30;

struct StorageFile {
  fs::path path;
  std::string name;  // as the user knows it (display_path)
  std::unique_ptr<McapReader> mcap;
  std::unique_ptr<Db3Reader> db3;
};

StorageFile open_storage(const fs::path& path, const std::string& storage) {
  StorageFile file;
  file.path = path;
  file.name = display_path(path);
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw IoError(file.name + ": not found");
  const std::string extension = path.extension().string();
  try {
    if (extension == ".mcap" || (extension != ".db3" && storage == "mcap"))
      file.mcap = std::make_unique<McapReader>(std::make_shared<FileBytes>(path, file.name));
    else
      file.db3 = std::make_unique<Db3Reader>(path);
  } catch (const BagFormatError& e) {
    throw IoError(file.name + ": " + e.what());
  }
  return file;
}

}  // namespace

struct Rosbag2Reader::Impl {
  fs::path path;
  std::string name;
  std::vector<StorageFile> files;
  std::vector<BagTopicInfo> topics;
  bool zstd_messages = false;  // compression_mode MESSAGE, compression_format zstd
  // serialization_format per topic as metadata.yaml declares it (rosbag2 goes by this).
  std::map<std::string, std::string> declared_formats;
};

namespace {

using RawMessage = Rosbag2Reader::RawMessage;

// The messages of one topic across the storage files, with errors that name the file, the
// topic and the message index.
class TopicCursor {
 public:
  TopicCursor(std::shared_ptr<const Rosbag2Reader::Impl> impl, std::string topic)
      : impl_(std::move(impl)), topic_(std::move(topic)) {
    const auto it = impl_->declared_formats.find(topic_);
    if (it != impl_->declared_formats.end()) declared_format_ = it->second;
  }

  // "<file>: topic '<topic>' message <index>" of the message last returned.
  std::string where() const { return where_index(index_ == 0 ? 0 : index_ - 1); }
  size_t index() const { return index_ - 1; }

  bool next(RawMessage& message) {
    try {
      while (file_ < impl_->files.size()) {
        if (!opened_) open_file();
        if (read_in_file(message)) {
          ++index_;
          if (impl_->zstd_messages) decompress(message);
          return true;
        }
        mcap_.reset();
        db3_.reset();
        opened_ = false;
        ++file_;
      }
      return false;
    } catch (const BagFormatError& e) {
      throw IoError(where_index(index_) + ": " + e.what());
    }
  }

 private:
  std::string where_index(size_t index) const {
    const size_t f = std::min(file_, impl_->files.size() - 1);
    return impl_->files[f].name + ": topic '" + topic_ + "' message " + std::to_string(index);
  }

  void open_file() {
    const StorageFile& file = impl_->files[file_];
    opened_ = true;
    if (file.mcap) {
      std::set<uint16_t> ids;
      for (const auto& [id, channel] : file.mcap->channels())
        if (channel.topic == topic_) ids.insert(id);
      if (!ids.empty()) mcap_.emplace(file.mcap->messages(ids));
    } else {
      for (const auto& t : file.db3->topics())
        if (t.name == topic_) {
          db3_.emplace(file.db3->messages(t.id));
          serialization_ = t.serialization_format;
          type_ = t.type;
        }
    }
  }

  bool read_in_file(RawMessage& message) {
    if (mcap_) {
      McapMessage m;
      if (!mcap_->next(m)) return false;
      check_serialization(declared_format_.empty() ? m.channel->message_encoding
                                                   : declared_format_);
      message.type = m.channel->schema_name;
      message.log_time_ns = static_cast<TimeNs>(m.log_time);
      message.data = m.data;
      message.size = m.size;
      return true;
    }
    if (db3_) {
      Db3Message m;
      if (!db3_->next(m)) return false;
      check_serialization(declared_format_.empty() ? serialization_ : declared_format_);
      message.type = type_;
      message.log_time_ns = m.timestamp_ns;
      message.data = m.data;
      message.size = m.size;
      return true;
    }
    return false;
  }

  void check_serialization(const std::string& format) const {
    // "" is what some early rosbag2 writers recorded (nebula's VLS-128 test bag): ROS 2's
    // default, CDR; a message that is not CDR still fails its encapsulation check.
    if (format != "cdr" && !format.empty())
      throw BagFormatError("serialization format '" + format + "'; Keel decodes ROS 2 cdr");
  }

  void decompress(RawMessage& message) {
    const unsigned long long size = ZSTD_getFrameContentSize(message.data, message.size);
    if (size == ZSTD_CONTENTSIZE_ERROR || size == ZSTD_CONTENTSIZE_UNKNOWN)
      throw IoError(where() +
                    ": not a zstd frame with its size (metadata.yaml says the "
                    "messages are zstd-compressed)");
    if (size > kMaxMessageBytes)
      throw IoError(where() + ": decompresses to " + std::to_string(size) +
                    " bytes, beyond the reader's limit");
    buffer_.resize(size);
    const size_t n = ZSTD_decompress(buffer_.data(), buffer_.size(), message.data, message.size);
    if (ZSTD_isError(n) || n != size)
      throw IoError(where() + ": zstd: " +
                    (ZSTD_isError(n) ? ZSTD_getErrorName(n) : "size differs from the frame's"));
    message.data = buffer_.data();
    message.size = buffer_.size();
  }

  std::shared_ptr<const Rosbag2Reader::Impl> impl_;
  std::string topic_;
  size_t file_ = 0;
  bool opened_ = false;
  size_t index_ = 0;  // messages returned so far
  std::optional<McapReader::Cursor> mcap_;
  std::optional<Db3Reader::Cursor> db3_;
  std::string serialization_, type_, declared_format_;
  std::vector<uint8_t> buffer_;
};

// Each message's type must be one of `accepted` (a topic may mix types in MCAP: one channel
// per publisher); returns its index in `accepted`.
size_t expect_type(const RawMessage& m, std::initializer_list<const char*> accepted,
                   const std::string& what) {
  size_t i = 0;
  std::string list;
  for (const char* type : accepted) {
    if (m.type == type) return i;
    list += (list.empty() ? "" : " or ") + std::string(type);
    ++i;
  }
  throw IoError(what + ": message type " +
                (m.type.empty() ? std::string("unknown (no schema)") : std::string(m.type)) +
                "; expected " + list);
}

TimeNs stamp_of(TimeNs header_stamp_ns, const RawMessage& m) {
  return header_stamp_ns == 0 ? m.log_time_ns : header_stamp_ns;
}

// Runs `body(message, index, what)` over a topic, typing its errors with the message.
template <typename Body>
void for_each_typed(const std::shared_ptr<Rosbag2Reader::Impl>& impl, const std::string& topic,
                    Body&& body) {
  TopicCursor cursor(impl, topic);
  RawMessage m;
  while (cursor.next(m)) {
    const std::string what = cursor.where();
    try {
      body(m, cursor.index(), what);
    } catch (const BagFormatError& e) {
      throw IoError(what + ": " + e.what());
    }
  }
}

class Ros2ScanSource : public ScanSource {
 public:
  Ros2ScanSource(std::shared_ptr<const Rosbag2Reader::Impl> impl, std::string topic, size_t count,
                 ScanReadOptions options)
      : cursor_(std::move(impl), std::move(topic)), count_(count), options_(std::move(options)) {}
  size_t size() const override { return count_; }
  std::string current_source() const override { return returned_ ? cursor_.where() : ""; }

  bool next(PointCloud& cloud) override {
    RawMessage m;
    if (!cursor_.next(m)) return false;
    returned_ = true;
    const std::string what = cursor_.where();
    const bool packets =
        expect_type(m, {"sensor_msgs/msg/PointCloud2", kVelodyneScanRos2}, what) == 1;
    if (packets) {
      cloud = decode_velodyne_message(m.data, m.size, true, stamp_of(0, m), options_, what,
                                      scratch_);
    } else {
      ros2::PointCloud2 msg;
      try {
        msg = ros2::decode_point_cloud2(m.data, m.size);
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
  size_t count_;
  ScanReadOptions options_;
  bool returned_ = false;
  TimeNs previous_ns_ = 0;
  std::vector<lidar::VelodynePoint> scratch_;
};

class Ros2ImageSource : public ImageSource {
 public:
  Ros2ImageSource(std::shared_ptr<const Rosbag2Reader::Impl> impl, std::string topic, size_t count)
      : cursor_(std::move(impl), std::move(topic)), count_(count) {}
  size_t size() const override { return count_; }
  std::string current_source() const override { return returned_ ? cursor_.where() : ""; }

  bool next(ImageFrame& frame, bool decode) override {
    RawMessage m;
    if (!cursor_.next(m)) return false;
    returned_ = true;
    const std::string what = cursor_.where();
    const size_t kind =
        expect_type(m, {"sensor_msgs/msg/Image", "sensor_msgs/msg/CompressedImage"}, what);
    TimeNs t_ns = 0;
    try {
      if (kind == 0) {
        const ros2::Image msg = ros2::decode_image(m.data, m.size);
        t_ns = stamp_of(msg.stamp_ns, m);
        frame = unpack_image(msg.view, decode, what);
      } else {
        const ros2::CompressedImage msg = ros2::decode_compressed_image(m.data, m.size);
        t_ns = stamp_of(msg.stamp_ns, m);
        frame = decode_image(std::vector<uint8_t>(msg.data, msg.data + msg.size), what);
        if (!decode) frame.pixels.clear();
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
  size_t count_;
  bool returned_ = false;
  TimeNs previous_ns_ = 0;
};

}  // namespace

Rosbag2Reader::Rosbag2Reader(const fs::path& path) : impl_(std::make_shared<Impl>()) {
  impl_->path = path;
  impl_->name = display_path(path);
  std::error_code ec;
  if (fs::is_directory(path, ec)) {
    const fs::path metadata_path = path / "metadata.yaml";
    if (!fs::is_regular_file(metadata_path, ec))
      throw IoError(impl_->name +
                    ": no metadata.yaml in the rosbag2 folder (`ros2 bag reindex` "
                    "writes one for a recording that did not finish)");
    const Rosbag2Metadata metadata = read_rosbag2_metadata(metadata_path);
    const std::string metadata_name = display_path(metadata_path);
    const std::string mode = metadata.compression_mode;
    if (mode == "FILE" || mode == "file")
      throw IoError(metadata_name +
                    ": compression_mode FILE (whole files compressed) is not "
                    "supported; decompress the bag first (ros2 bag convert)");
    if (mode == "MESSAGE" || mode == "message") {
      if (metadata.compression_format != "zstd")
        throw IoError(metadata_name + ": compression_format '" + metadata.compression_format +
                      "' is not supported (zstd is)");
      impl_->zstd_messages = true;
    }
    for (const auto& t : metadata.topics)
      if (!t.serialization_format.empty()) impl_->declared_formats[t.name] = t.serialization_format;
    for (const auto& rel : metadata.relative_file_paths) {
      fs::path file = path / rel;
      // rosbag2 before Foxy wrote paths starting with the bag folder's own name.
      if (!fs::exists(file, ec) && fs::exists(path / fs::path(rel).filename(), ec))
        file = path / fs::path(rel).filename();
      if (!fs::exists(file, ec))
        throw IoError(metadata_name + ": relative_file_paths: '" + rel + "' not found (" +
                      display_path(file) + ")");
      impl_->files.push_back(open_storage(file, metadata.storage_identifier));
    }
  } else if (fs::is_regular_file(path, ec)) {
    impl_->files.push_back(open_storage(path, ""));
  } else {
    throw IoError(impl_->name + ": bag not found");
  }

  std::map<std::string, BagTopicInfo> by_topic;
  auto add = [&](const std::string& topic, const std::string& type, uint64_t messages) {
    BagTopicInfo& info = by_topic[topic];
    if (info.topic.empty()) info.topic = topic, info.datatype = type;
    info.messages += messages;
  };
  for (const auto& file : impl_->files) {
    if (file.mcap)
      for (const auto& [id, channel] : file.mcap->channels())
        add(channel.topic, channel.schema_name, channel.messages);
    else
      for (const auto& t : file.db3->topics()) add(t.name, t.type, t.messages);
  }
  for (auto& [name, info] : by_topic) impl_->topics.push_back(std::move(info));
}

Rosbag2Reader::~Rosbag2Reader() = default;

const fs::path& Rosbag2Reader::path() const { return impl_->path; }
const std::vector<BagTopicInfo>& Rosbag2Reader::topics() const { return impl_->topics; }

std::vector<fs::path> Rosbag2Reader::files() const {
  std::vector<fs::path> out;
  for (const auto& f : impl_->files) out.push_back(f.path);
  return out;
}

std::string Rosbag2Reader::damage() const {
  std::string out;
  for (const auto& f : impl_->files)
    if (f.mcap && !f.mcap->complete())
      out += (out.empty() ? "" : "; ") + f.name +
             " ends without its MCAP footer (cut short?): topics recorded after the cut are "
             "missing";
  return out;
}

void Rosbag2Reader::for_each_message(
    const std::string& topic_name,
    const std::function<void(const RawMessage&, size_t index)>& body) const {
  topic(topic_name);
  TopicCursor cursor(impl_, topic_name);
  RawMessage m;
  while (cursor.next(m)) body(m, cursor.index());
}

void Rosbag2Reader::for_each_raw_message(
    const std::string& topic_name,
    const std::function<bool(const BagRawMessage&, size_t index)>& body) const {
  topic(topic_name);
  TopicCursor cursor(impl_, topic_name);
  RawMessage m;
  while (cursor.next(m))
    if (!body({m.type, m.log_time_ns, m.data, m.size, true}, cursor.index())) return;
}

ImuSeries Rosbag2Reader::read_imu(const std::string& topic_name) const {
  ImuSeries out;
  out.reserve(topic(topic_name).messages);
  for_each_typed(impl_, topic_name, [&](const RawMessage& m, size_t i, const std::string& what) {
    expect_type(m, {"sensor_msgs/msg/Imu"}, what);
    const ros2::Imu msg = ros2::decode_imu(m.data, m.size);
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

DvlSeries Rosbag2Reader::read_dvl(const std::string& topic_name) const {
  topic(topic_name);
  DvlSeries out;
  for_each_typed(impl_, topic_name, [&](const RawMessage& m, size_t i, const std::string& what) {
    const size_t kind = expect_type(m,
                                    {"geometry_msgs/msg/TwistWithCovarianceStamped",
                                     "geometry_msgs/msg/TwistStamped", "dvl_msgs/msg/DVL"},
                                    what);
    if (kind == 2) {  // Water Linked A50 (a50_messages.h)
      const A50Dvl msg = decode_a50_ros2(m.data, m.size);
      const TimeNs t_ns = stamp_of(msg.stamp_ns, m);
      check_increasing(what, i, t_ns, out.empty() ? 0 : out.back().t_ns);
      out.push_back(a50_dvl_sample(msg, t_ns, what));
      return;
    }
    const ros2::Twist msg = kind == 0 ? ros2::decode_twist_with_covariance_stamped(m.data, m.size)
                                      : ros2::decode_twist_stamped(m.data, m.size);
    DvlSample s;
    s.t_ns = stamp_of(msg.stamp_ns, m);
    check_increasing(what, i, s.t_ns, out.empty() ? 0 : out.back().t_ns);
    const auto& v = msg.linear;
    s.velocity_m_s = finite_vector(v.x(), v.y(), v.z(), what + " twist.linear");
    out.push_back(s);
  });
  return out;
}

GnssSeries Rosbag2Reader::read_gnss(const std::string& topic_name) const {
  topic(topic_name);
  GnssSeries out;
  for_each_typed(impl_, topic_name, [&](const RawMessage& m, size_t i, const std::string& what) {
    expect_type(m, {"sensor_msgs/msg/NavSatFix"}, what);
    const ros2::NavSatFix msg = ros2::decode_nav_sat_fix(m.data, m.size);
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

Trajectory Rosbag2Reader::read_trajectory(const std::string& topic_name) const {
  topic(topic_name);
  Trajectory out;
  for_each_typed(impl_, topic_name, [&](const RawMessage& m, size_t i, const std::string& what) {
    const size_t kind =
        expect_type(m, {"geometry_msgs/msg/PoseStamped", "nav_msgs/msg/Odometry"}, what);
    const ros2::Pose msg = kind == 0 ? ros2::decode_pose_stamped(m.data, m.size)
                                     : ros2::decode_odometry(m.data, m.size);
    StampedPose pose;
    pose.t_ns = stamp_of(msg.stamp_ns, m);
    check_increasing(what, i, pose.t_ns, out.empty() ? 0 : out.back().t_ns);
    pose.T_world_body = checked_pose(msg.orientation, msg.position, what + " pose");
    out.push_back(pose);
  });
  return out;
}

std::vector<StaticTransform> Rosbag2Reader::read_static_transforms(
    const std::string& topic_name) const {
  std::vector<StaticTransform> out;
  if (!has_topic(topic_name)) return out;
  for_each_typed(impl_, topic_name, [&](const RawMessage& m, size_t, const std::string& what) {
    expect_type(m, {"tf2_msgs/msg/TFMessage"}, what);
    for (const auto& t : ros2::decode_tf_message(m.data, m.size)) {
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

std::unique_ptr<ScanSource> Rosbag2Reader::open_scans(const std::string& topic_name,
                                                      ScanReadOptions options) const {
  const BagTopicInfo& info = topic(topic_name);
  check_packet_options(display_path(path()), topic_name, info.datatype == kVelodyneScanRos2,
                       options);
  return std::make_unique<Ros2ScanSource>(impl_, topic_name, info.messages, std::move(options));
}

std::unique_ptr<ImageSource> Rosbag2Reader::open_images(const std::string& topic_name) const {
  const size_t count = topic(topic_name).messages;
  return std::make_unique<Ros2ImageSource>(impl_, topic_name, count);
}

}  // namespace keel::io
