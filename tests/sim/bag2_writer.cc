#include "tests/sim/bag2_writer.h"

#include <yaml-cpp/yaml.h>

#include <Eigen/Geometry>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "tests/sim/cdr_writer.h"
#include "tests/sim/db3_writer.h"
#include "tests/sim/mcap_writer.h"

namespace keel::sim {

namespace fs = std::filesystem;

namespace {

// The .msg texts of ROS 2 common_interfaces (comments dropped), concatenated as the ros2msg
// schema encoding wants: the type itself, then each dependency after a line of 80 '=' and
// "MSG: <package>/<Type>".
const std::map<std::string, std::string>& msg_texts() {
  static const std::map<std::string, std::string> texts = {
      {"builtin_interfaces/Time", "int32 sec\nuint32 nanosec\n"},
      {"std_msgs/Header", "builtin_interfaces/Time stamp\nstring frame_id\n"},
      {"geometry_msgs/Vector3", "float64 x\nfloat64 y\nfloat64 z\n"},
      {"geometry_msgs/Point", "float64 x\nfloat64 y\nfloat64 z\n"},
      {"geometry_msgs/Quaternion", "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n"},
      {"geometry_msgs/Pose", "Point position\nQuaternion orientation\n"},
      {"geometry_msgs/PoseWithCovariance", "Pose pose\nfloat64[36] covariance\n"},
      {"geometry_msgs/Twist", "Vector3 linear\nVector3 angular\n"},
      {"geometry_msgs/TwistWithCovariance", "Twist twist\nfloat64[36] covariance\n"},
      {"sensor_msgs/PointField",
       "uint8 INT8 = 1\nuint8 UINT8 = 2\nuint8 INT16 = 3\nuint8 UINT16 = 4\nuint8 INT32 = 5\n"
       "uint8 UINT32 = 6\nuint8 FLOAT32 = 7\nuint8 FLOAT64 = 8\nstring name\nuint32 offset\n"
       "uint8 datatype\nuint32 count\n"},
      {"sensor_msgs/Imu",
       "std_msgs/Header header\ngeometry_msgs/Quaternion orientation\n"
       "float64[9] orientation_covariance\ngeometry_msgs/Vector3 angular_velocity\n"
       "float64[9] angular_velocity_covariance\ngeometry_msgs/Vector3 linear_acceleration\n"
       "float64[9] linear_acceleration_covariance\n"},
      {"sensor_msgs/PointCloud2",
       "std_msgs/Header header\nuint32 height\nuint32 width\nPointField[] fields\n"
       "bool is_bigendian\nuint32 point_step\nuint32 row_step\nuint8[] data\nbool is_dense\n"},
      {"sensor_msgs/Image",
       "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\n"
       "uint8 is_bigendian\nuint32 step\nuint8[] data\n"},
      {"geometry_msgs/PoseStamped", "std_msgs/Header header\nPose pose\n"},
      {"geometry_msgs/TwistWithCovarianceStamped",
       "std_msgs/Header header\nTwistWithCovariance twist\n"},
      {"geometry_msgs/Transform", "Vector3 translation\nQuaternion rotation\n"},
      {"geometry_msgs/TransformStamped",
       "std_msgs/Header header\nstring child_frame_id\nTransform transform\n"},
      {"tf2_msgs/TFMessage", "geometry_msgs/TransformStamped[] transforms\n"},
      {"dvl_msgs/DVLBeam",
       "int64 id\nfloat64 velocity\nfloat64 distance\nfloat64 rssi\nfloat64 nsd\nbool valid\n"},
      {"dvl_msgs/DVL",
       "std_msgs/Header header\nfloat64 time\ngeometry_msgs/Vector3 velocity\nfloat64 fom\n"
       "float64[9] covariance\nfloat64 altitude\nDVLBeam[] beams\nbool velocity_valid\n"
       "int64 status\nint64 time_of_validity\nint64 time_of_transmission\nstring form\n"},
      {"nav_msgs/Odometry",
       "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/PoseWithCovariance pose\n"
       "geometry_msgs/TwistWithCovariance twist\n"},
  };
  return texts;
}

const std::map<std::string, std::vector<std::string>>& dependencies() {
  static const std::map<std::string, std::vector<std::string>> deps = {
      {"sensor_msgs/Imu",
       {"std_msgs/Header", "builtin_interfaces/Time", "geometry_msgs/Quaternion",
        "geometry_msgs/Vector3"}},
      {"sensor_msgs/PointCloud2",
       {"std_msgs/Header", "builtin_interfaces/Time", "sensor_msgs/PointField"}},
      {"sensor_msgs/Image", {"std_msgs/Header", "builtin_interfaces/Time"}},
      {"geometry_msgs/PoseStamped",
       {"std_msgs/Header", "builtin_interfaces/Time", "geometry_msgs/Pose", "geometry_msgs/Point",
        "geometry_msgs/Quaternion"}},
      {"geometry_msgs/TwistWithCovarianceStamped",
       {"std_msgs/Header", "builtin_interfaces/Time", "geometry_msgs/TwistWithCovariance",
        "geometry_msgs/Twist", "geometry_msgs/Vector3"}},
      {"tf2_msgs/TFMessage",
       {"geometry_msgs/TransformStamped", "std_msgs/Header", "builtin_interfaces/Time",
        "geometry_msgs/Transform", "geometry_msgs/Vector3", "geometry_msgs/Quaternion"}},
      {"dvl_msgs/DVL",
       {"std_msgs/Header", "builtin_interfaces/Time", "geometry_msgs/Vector3", "dvl_msgs/DVLBeam"}},
      {"nav_msgs/Odometry",
       {"std_msgs/Header", "builtin_interfaces/Time", "geometry_msgs/PoseWithCovariance",
        "geometry_msgs/Pose", "geometry_msgs/Point", "geometry_msgs/Quaternion",
        "geometry_msgs/TwistWithCovariance", "geometry_msgs/Twist", "geometry_msgs/Vector3"}},
  };
  return deps;
}

// "sensor_msgs/msg/Imu" -> its ros2msg schema text.
std::string definition(const std::string& type) {
  const std::string short_name = type.substr(0, type.find('/')) + type.substr(type.rfind('/'));
  std::string text = msg_texts().at(short_name);
  for (const auto& dep : dependencies().at(short_name))
    text += std::string(80, '=') + "\nMSG: " + dep + "\n" + msg_texts().at(dep);
  return text;
}

void header(CdrWriter& w, const std::string& frame, TimeNs t_ns) {
  w.i32(static_cast<int32_t>(t_ns / 1000000000));
  w.u32(static_cast<uint32_t>(t_ns % 1000000000));
  w.string(frame);
}

void vector3(CdrWriter& w, const Eigen::Vector3d& v) {
  w.f64(v.x());
  w.f64(v.y());
  w.f64(v.z());
}

void write_pose(CdrWriter& w, const Pose3& T) {
  vector3(w, T.translation());
  const Eigen::Quaterniond q(T.linear());
  w.f64(q.x());
  w.f64(q.y());
  w.f64(q.z());
  w.f64(q.w());
}

void zeros(CdrWriter& w, int n) {
  for (int i = 0; i < n; ++i) w.f64(0.0);
}

}  // namespace

struct Bag2Writer::File {
  std::unique_ptr<McapWriter> mcap;
  std::unique_ptr<Db3Writer> db3;
  std::map<std::string, int64_t> ids;  // topic -> channel or topic id in this file
  uint64_t bytes() const { return mcap ? mcap->bytes_written() : db3->bytes_written(); }
};

Bag2Writer::Bag2Writer(const std::string& folder, Bag2Options options)
    : folder_(folder), options_(std::move(options)) {
  if (options_.storage != "mcap" && options_.storage != "sqlite3")
    throw std::invalid_argument("--bag2: storage '" + options_.storage +
                                "': expected mcap or sqlite3");
  std::error_code ec;
  fs::create_directories(folder_, ec);
  if (ec) throw std::runtime_error("cannot create " + folder_ + ": " + ec.message());
  open_file();
}

Bag2Writer::~Bag2Writer() {
  try {
    close();
  } catch (...) {
  }
}

void Bag2Writer::open_file() {
  FileInfo info;
  info.name = fs::path(folder_).filename().string() + "_" + std::to_string(files_.size()) +
              (options_.storage == "mcap" ? ".mcap" : ".db3");
  const std::string path = (fs::path(folder_) / info.name).string();
  file_ = std::make_unique<File>();
  if (options_.storage == "mcap") {
    McapWriterOptions mcap;
    mcap.compression = options_.compression == "none" ? "" : options_.compression;
    file_->mcap = std::make_unique<McapWriter>(path, mcap);
  } else {
    file_->db3 = std::make_unique<Db3Writer>(path);
  }
  files_.push_back(info);
}

void Bag2Writer::close_file() {
  if (!file_) return;
  if (file_->mcap) file_->mcap->close();
  if (file_->db3) file_->db3->close();
  file_.reset();
}

void Bag2Writer::record(const std::string& topic, const std::string& type, TimeNs t_ns,
                        const std::vector<uint8_t>& cdr) {
  if (options_.max_file_bytes > 0 && files_.back().messages > 0 &&
      file_->bytes() >= options_.max_file_bytes) {
    close_file();
    open_file();
  }
  auto it = file_->ids.find(topic);
  if (it == file_->ids.end()) {
    int64_t id;
    if (file_->mcap)
      id = file_->mcap->add_channel(topic,
                                    file_->mcap->add_schema(type, "ros2msg", definition(type)));
    else
      id = file_->db3->add_topic(topic, type, definition(type));
    it = file_->ids.emplace(topic, id).first;
  }
  if (file_->mcap)
    file_->mcap->write(static_cast<uint16_t>(it->second), static_cast<uint64_t>(t_ns), cdr);
  else
    file_->db3->write(it->second, t_ns, cdr);
  FileInfo& info = files_.back();
  info.start_ns = info.messages == 0 ? t_ns : std::min(info.start_ns, t_ns);
  info.end_ns = info.messages == 0 ? t_ns : std::max(info.end_ns, t_ns);
  ++info.messages;
  TopicInfo& topic_info = topics_[topic];
  topic_info.type = type;
  ++topic_info.messages;
}

void Bag2Writer::imu(const std::string& topic, const std::string& frame, TimeNs t_ns,
                     const Eigen::Vector3d& gyro, const Eigen::Vector3d& accel) {
  CdrWriter w;
  header(w, frame, t_ns);
  w.f64(0), w.f64(0), w.f64(0), w.f64(1);  // orientation
  w.f64(-1.0);                             // orientation_covariance[0] = -1: no estimate
  zeros(w, 8);
  vector3(w, gyro);
  zeros(w, 9);
  vector3(w, accel);
  zeros(w, 9);
  record(topic, "sensor_msgs/msg/Imu", t_ns, w.bytes());
}

void Bag2Writer::twist(const std::string& topic, const std::string& frame, TimeNs t_ns,
                       const Eigen::Vector3d& v, double sigma) {
  CdrWriter w;
  header(w, frame, t_ns);
  vector3(w, v);
  zeros(w, 3);  // angular
  for (int i = 0; i < 36; ++i) {
    const int r = i / 6, c = i % 6;
    w.f64(r != c ? 0.0 : r < 3 ? sigma * sigma : -1.0);  // angular part unknown
  }
  record(topic, "geometry_msgs/msg/TwistWithCovarianceStamped", t_ns, w.bytes());
}

void Bag2Writer::a50_dvl(const std::string& topic, const std::string& frame, const io::A50Dvl& m) {
  CdrWriter w;
  header(w, frame, m.stamp_ns);
  w.f64(m.time_ms);
  vector3(w, m.velocity_m_s);
  w.f64(m.fom_m_s);
  for (double c : m.covariance_m2_s2) w.f64(c);
  w.f64(m.altitude_m);
  w.sequence(static_cast<uint32_t>(m.beams.size()));
  for (const io::A50Beam& b : m.beams) {
    w.i64(b.id);
    w.f64(b.velocity_m_s), w.f64(b.distance_m), w.f64(b.rssi_dbm), w.f64(b.nsd_dbm);
    w.boolean(b.valid);
  }
  w.boolean(m.velocity_valid);
  w.i64(m.status);
  w.i64(0), w.i64(0);  // time_of_validity, time_of_transmission (not read)
  w.string("json_v3");
  record(topic, "dvl_msgs/msg/DVL", m.stamp_ns, w.bytes());
}

void Bag2Writer::cloud(const std::string& topic, const std::string& frame,
                       const PointCloud& cloud) {
  struct Field {
    const char* name;
    uint32_t offset;
    uint8_t type;
  };
  std::vector<Field> fields;
  uint32_t offset = 0;
  for (const char* axis : {"x", "y", "z"}) fields.push_back({axis, offset, 7}), offset += 4;
  if (cloud.has_intensity()) fields.push_back({"intensity", offset, 7}), offset += 4;
  if (cloud.has_ring()) fields.push_back({"ring", offset, 4}), offset += 2;
  if (cloud.has_time()) fields.push_back({"time", offset, 7}), offset += 4;
  std::vector<uint8_t> data(static_cast<size_t>(offset) * cloud.size());
  uint8_t* out = data.data();
  for (size_t i = 0; i < cloud.size(); ++i) {
    std::memcpy(out, cloud.xyz[i].data(), 12), out += 12;
    if (cloud.has_intensity()) std::memcpy(out, &cloud.intensity[i], 4), out += 4;
    if (cloud.has_ring()) std::memcpy(out, &cloud.ring[i], 2), out += 2;
    if (cloud.has_time()) std::memcpy(out, &cloud.time_s[i], 4), out += 4;
  }
  CdrWriter w;
  header(w, frame, cloud.t_ns);
  w.u32(1);
  w.u32(static_cast<uint32_t>(cloud.size()));
  w.sequence(static_cast<uint32_t>(fields.size()));
  for (const auto& f : fields) {
    w.string(f.name);
    w.u32(f.offset);
    w.u8(f.type);
    w.u32(1);
  }
  w.boolean(false);
  w.u32(offset);
  w.u32(offset * static_cast<uint32_t>(cloud.size()));
  w.byte_sequence(data.data(), data.size());
  w.boolean(true);
  record(topic, "sensor_msgs/msg/PointCloud2", cloud.t_ns, w.bytes());
}

void Bag2Writer::image(const std::string& topic, const std::string& frame, TimeNs t_ns,
                       const cv::Mat& gray) {
  CdrWriter w;
  header(w, frame, t_ns);
  w.u32(static_cast<uint32_t>(gray.rows));
  w.u32(static_cast<uint32_t>(gray.cols));
  w.string("mono8");
  w.u8(0);
  w.u32(static_cast<uint32_t>(gray.cols));
  std::vector<uint8_t> pixels(static_cast<size_t>(gray.rows) * gray.cols);
  for (int r = 0; r < gray.rows; ++r)
    std::memcpy(&pixels[static_cast<size_t>(r) * gray.cols], gray.ptr(r), gray.cols);
  w.byte_sequence(pixels.data(), pixels.size());
  record(topic, "sensor_msgs/msg/Image", t_ns, w.bytes());
}

void Bag2Writer::transforms(const std::string& topic, TimeNs t_ns, const TransformEdges& edges) {
  CdrWriter w;
  w.u32(static_cast<uint32_t>(edges.size()));
  for (const auto& [parent, child, T] : edges) {
    header(w, parent, t_ns);
    w.string(child);
    write_pose(w, T);  // Transform: translation then rotation, as Pose's position, orientation
  }
  record(topic, "tf2_msgs/msg/TFMessage", t_ns, w.bytes());
}

void Bag2Writer::pose(const std::string& topic, const std::string& frame, const StampedPose& p) {
  CdrWriter w;
  header(w, frame, p.t_ns);
  write_pose(w, p.T_world_body);
  record(topic, "geometry_msgs/msg/PoseStamped", p.t_ns, w.bytes());
}

void Bag2Writer::odometry(const std::string& topic, const std::string& frame,
                          const std::string& child_frame, const StampedPose& p) {
  CdrWriter w;
  header(w, frame, p.t_ns);
  w.string(child_frame);
  write_pose(w, p.T_world_body);
  zeros(w, 36);      // pose covariance
  zeros(w, 6 + 36);  // twist and its covariance
  record(topic, "nav_msgs/msg/Odometry", p.t_ns, w.bytes());
}

void Bag2Writer::close() {
  if (closed_) return;
  closed_ = true;
  close_file();
  // metadata.yaml (rosbag2_storage's rosbag2_bagfile_information, version 8).
  TimeNs start = 0, end = 0;
  uint64_t total = 0;
  bool any = false;
  for (const auto& f : files_) {
    if (f.messages == 0) continue;
    start = any ? std::min(start, f.start_ns) : f.start_ns;
    end = any ? std::max(end, f.end_ns) : f.end_ns;
    total += f.messages;
    any = true;
  }
  YAML::Emitter y;
  y << YAML::BeginMap << YAML::Key << "rosbag2_bagfile_information" << YAML::Value
    << YAML::BeginMap;
  y << YAML::Key << "version" << YAML::Value << 8;
  y << YAML::Key << "storage_identifier" << YAML::Value << options_.storage;
  y << YAML::Key << "duration" << YAML::Value << YAML::BeginMap << YAML::Key << "nanoseconds"
    << YAML::Value << (end - start) << YAML::EndMap;
  y << YAML::Key << "starting_time" << YAML::Value << YAML::BeginMap << YAML::Key
    << "nanoseconds_since_epoch" << YAML::Value << start << YAML::EndMap;
  y << YAML::Key << "message_count" << YAML::Value << total;
  y << YAML::Key << "topics_with_message_count" << YAML::Value << YAML::BeginSeq;
  for (const auto& [name, t] : topics_) {
    y << YAML::BeginMap << YAML::Key << "topic_metadata" << YAML::Value << YAML::BeginMap;
    y << YAML::Key << "name" << YAML::Value << name;
    y << YAML::Key << "type" << YAML::Value << t.type;
    y << YAML::Key << "serialization_format" << YAML::Value << "cdr";
    y << YAML::Key << "offered_qos_profiles" << YAML::Value << "";
    y << YAML::Key << "type_description_hash" << YAML::Value << "" << YAML::EndMap;
    y << YAML::Key << "message_count" << YAML::Value << t.messages << YAML::EndMap;
  }
  y << YAML::EndSeq;
  y << YAML::Key << "compression_format" << YAML::Value << "";
  y << YAML::Key << "compression_mode" << YAML::Value << "";
  y << YAML::Key << "relative_file_paths" << YAML::Value << YAML::BeginSeq;
  for (const auto& f : files_) y << f.name;
  y << YAML::EndSeq;
  y << YAML::Key << "files" << YAML::Value << YAML::BeginSeq;
  for (const auto& f : files_) {
    y << YAML::BeginMap << YAML::Key << "path" << YAML::Value << f.name;
    y << YAML::Key << "starting_time" << YAML::Value << YAML::BeginMap << YAML::Key
      << "nanoseconds_since_epoch" << YAML::Value << f.start_ns << YAML::EndMap;
    y << YAML::Key << "duration" << YAML::Value << YAML::BeginMap << YAML::Key << "nanoseconds"
      << YAML::Value << (f.end_ns - f.start_ns) << YAML::EndMap;
    y << YAML::Key << "message_count" << YAML::Value << f.messages << YAML::EndMap;
  }
  y << YAML::EndSeq;
  y << YAML::EndMap << YAML::EndMap;
  std::ofstream out(fs::path(folder_) / "metadata.yaml");
  out << y.c_str() << "\n";
  if (!out) throw std::runtime_error("cannot write " + folder_ + "/metadata.yaml");
}

}  // namespace keel::sim
