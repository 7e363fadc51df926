#include "worker/init/bag_survey.h"

#include <algorithm>
#include <cstdio>
#include <iomanip>

#include "worker/io/display_path.h"

namespace keel::init {

namespace {

std::string fixed(double x, int digits) {
  char b[48];
  std::snprintf(b, sizeof(b), "%.*f", digits, x);
  return b;
}

void add_rate_and_gaps(TopicSurvey& t, std::vector<TimeNs>& stamps) {
  if (stamps.empty()) return;
  // Rates from stamps in time order: a topic's header stamps may arrive out of order.
  std::sort(stamps.begin(), stamps.end());
  t.first_ns = stamps.front();
  t.last_ns = stamps.back();
  if (stamps.size() < 2 || t.last_ns <= t.first_ns) return;
  t.rate_hz = static_cast<double>(stamps.size() - 1) / t.span_s();
  std::vector<double> dt;
  for (size_t i = 1; i < stamps.size(); ++i) dt.push_back(ns_to_seconds(stamps[i] - stamps[i - 1]));
  std::vector<double> sorted = dt;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const double median = sorted[sorted.size() / 2];
  for (double d : dt) {
    t.max_gap_s = std::max(t.max_gap_s, d);
    if (median > 0.0 && d > 2.5 * median) ++t.gaps;
  }
}

TopicSurvey survey_topic(const io::BagSource& bag, const io::BagTopicInfo& info) {
  TopicSurvey t;
  t.topic = info.topic;
  t.type = info.datatype;
  t.plain_type = plain_type(info.datatype);
  t.header_stamps = has_header(info.datatype);
  std::vector<TimeNs> stamps;
  stamps.reserve(info.messages);
  std::optional<io::BagRawMessage> first_cloud;
  std::vector<uint8_t> first_cloud_bytes;
  TimeNs first_cloud_stamp = 0;
  const std::string name = io::display_path(bag.path());
  try {
    bag.for_each_raw_message(info.topic, [&](const io::BagRawMessage& m, size_t index) {
      const std::string what =
          name + ": topic '" + info.topic + "' message " + std::to_string(index);
      ++t.messages;
      TimeNs stamp = m.log_time_ns;
      if (t.header_stamps) {
        const Header h = read_header(m, what);
        if (h.stamp_ns != 0) stamp = h.stamp_ns;  // unset stamps: the receive time, as ingest
        if (index == 0) t.frame_id = h.frame_id;
      }
      stamps.push_back(stamp);
      if (index != 0 && !(t.plain_type == "sensor_msgs/NavSatFix" && !t.first_fix)) return true;
      if (t.plain_type == "sensor_msgs/PointCloud2") {
        // Kept until the rate is known: the time field's unit is read against the period.
        first_cloud_bytes.assign(m.data, m.data + m.size);
        first_cloud = m;
        first_cloud->data = first_cloud_bytes.data();
        first_cloud_stamp = stamp;
      } else if (t.plain_type == "sensor_msgs/Image" ||
                 t.plain_type == "sensor_msgs/CompressedImage") {
        t.image = read_image_info(m, what);
      } else if (t.plain_type == "nav_msgs/Odometry") {
        t.child_frame = read_odometry_child_frame(m, what);
      } else if (t.plain_type == "sensor_msgs/NavSatFix") {
        const Fix f = read_nav_sat_fix(m, what);
        if (f.status >= 0) t.first_fix = f;
      } else if (t.plain_type == "velodyne_msgs/VelodyneScan") {
        t.velodyne = read_velodyne_factory(m, what);
      }
      return true;
    });
  } catch (const std::exception& e) {
    t.error = e.what();
  }
  // The count the bag's index (ROS1) or metadata (rosbag2) states, as `rosbag info` shows it;
  // fewer readable messages are reported as the error above.
  t.messages = std::max(t.messages, info.messages);
  add_rate_and_gaps(t, stamps);
  if (first_cloud) {
    try {
      const CloudFields cloud =
          read_point_cloud2(*first_cloud, name + ": topic '" + info.topic + "' message 0");
      for (const auto& f : cloud.view.fields) t.fields.emplace_back(f.name, io::to_string(f.type));
      t.point_time =
          guess_point_time(cloud.view, first_cloud_stamp, t.rate_hz > 0.0 ? 1.0 / t.rate_hz : 0.0);
    } catch (const std::exception& e) {
      t.error = e.what();
    }
  }
  return t;
}

}  // namespace

BagSurvey survey_bag(const io::BagSource& bag) {
  BagSurvey s;
  s.bag = bag.path();
  for (const auto& info : bag.topics()) s.topics.push_back(survey_topic(bag, info));
  for (const char* topic : {"/tf_static", "/tf"}) {
    if (!bag.has_topic(topic)) continue;
    s.transforms = bag.read_static_transforms(topic);
    s.transforms_topic = topic;
    break;
  }
  return s;
}

void print_survey(const BagSurvey& survey, std::ostream& out) {
  out << io::display_path(survey.bag) << ": " << survey.topics.size() << " topics\n";
  size_t topic_w = 6, type_w = 5;
  for (const auto& t : survey.topics) {
    topic_w = std::max(topic_w, t.topic.size() + 2);
    type_w = std::max(type_w, t.type.size() + 2);
  }
  const int tw = static_cast<int>(topic_w), yw = static_cast<int>(type_w);
  out << std::left << std::setw(tw) << "topic" << std::setw(yw) << "type" << std::right
      << std::setw(8) << "count" << std::setw(10) << "rate_hz" << std::setw(10) << "span_s"
      << std::setw(6) << "gaps"
      << "  " << std::left << "frame_id\n";
  for (const auto& t : survey.topics) {
    out << std::left << std::setw(tw) << t.topic << std::setw(yw) << t.type << std::right
        << std::setw(8) << t.messages << std::setw(10) << fixed(t.rate_hz, 2) << std::setw(10)
        << fixed(t.span_s(), 2) << std::setw(6) << t.gaps << "  " << std::left
        << (t.frame_id.empty() ? "-" : t.frame_id) << "\n";
  }
  for (const auto& t : survey.topics) {
    std::string details;
    if (!t.header_stamps) details += "\n    stamps: receive times (the type has no header)";
    if (t.gaps)
      details +=
          "\n    " + std::to_string(t.gaps) + " gaps, the longest " + fixed(t.max_gap_s, 3) + " s";
    if (!t.fields.empty()) {
      details += "\n    fields:";
      for (const auto& [name, type] : t.fields) details += " " + name + ":" + type;
    }
    if (t.point_time) details += "\n    point time: " + t.point_time->evidence;
    if (t.image) {
      details += "\n    image: " + t.image->encoding;
      if (t.image->width)
        details += " " + std::to_string(t.image->width) + "x" + std::to_string(t.image->height);
    }
    if (!t.child_frame.empty()) details += "\n    child_frame_id: " + t.child_frame;
    if (t.first_fix)
      details += "\n    first fix: " + fixed(t.first_fix->latitude_deg, 7) + ", " +
                 fixed(t.first_fix->longitude_deg, 7) + ", " + fixed(t.first_fix->altitude_m, 2) +
                 " m";
    if (t.velodyne)
      details += "\n    packets: " + velodyne_product_name(t.velodyne->product) + ", " +
                 std::to_string(t.velodyne->packets) + " per message";
    if (!t.error.empty()) details += "\n    unreadable: " + t.error;
    if (!details.empty()) out << t.topic << ":" << details << "\n";
  }
  if (!survey.transforms_topic.empty()) {
    out << "transforms (" << survey.transforms_topic << "):";
    for (const auto& e : survey.transforms) out << " " << e.parent_frame << "->" << e.child_frame;
    out << "\n";
  }
}

}  // namespace keel::init
