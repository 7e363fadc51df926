#include "worker/init/mission_draft.h"

#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>

#include "worker/io/display_path.h"

namespace keel::init {

namespace {

namespace fs = std::filesystem;

std::string num(double x) {
  char b[40];
  std::snprintf(b, sizeof(b), "%.10g", std::abs(x) < 1e-12 ? 0.0 : x);
  return b;
}

// A rate as a user would write it: whole hertz when the data is within 2% of one.
std::string nice_rate(double r) {
  if (r >= 1.0 && std::abs(r - std::round(r)) <= 0.02 * r) return num(std::round(r));
  char b[32];
  std::snprintf(b, sizeof(b), "%.3g", r);
  return b;
}

// A sensor name from its topic: the first part that is not a generic word.
std::string name_from_topic(const std::string& topic) {
  static const std::set<std::string> kGeneric = {
      "points",     "data",       "raw",        "image_raw", "image_rect", "image",
      "compressed", "twist",      "velocity",   "fix",       "packets",    "velodyne_points",
      "cloud",      "pointcloud", "points_raw", "scan",      "ros",        "sensors",
      "sensor",     "dvl_data",   "navsat",     "gps_fix"};
  std::vector<std::string> parts;
  std::stringstream ss(topic);
  std::string part;
  while (std::getline(ss, part, '/'))
    if (!part.empty()) parts.push_back(part);
  std::string chosen = parts.empty() ? "sensor" : parts.back();
  for (const auto& p : parts)
    if (!kGeneric.count(p)) {
      chosen = p;
      break;
    }
  for (char& c : chosen)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') c = '_';
  return chosen;
}

bool contains(const std::string& s, const char* word) { return s.find(word) != std::string::npos; }

struct Sensor {
  const TopicSurvey* topic;
  std::string name, type;
  std::string note;        // a comment line on the entry
  bool commented = false;  // written as a commented-out block (needs user input)
};

class Writer {
 public:
  void line(const std::string& s) { out_ << s << "\n"; }
  std::string str() const { return out_.str(); }

 private:
  std::ostringstream out_;
};

}  // namespace

MissionDraft draft_mission(const BagSurvey& survey, const DraftOptions& options) {
  MissionDraft draft;
  std::vector<Sensor> sensors;
  std::vector<const TopicSurvey*> trajectories, unused;
  std::set<std::string> names;
  auto unique_name = [&](std::string n) {
    std::string candidate = n;
    for (int k = 2; names.count(candidate); ++k) candidate = n + "_" + std::to_string(k);
    names.insert(candidate);
    return candidate;
  };
  for (const auto& t : survey.topics) {
    const std::string& type = t.plain_type;
    Sensor s{&t, "", "", "", false};
    if (t.messages == 0) {
      unused.push_back(&t);
      continue;
    }
    if (type == "sensor_msgs/Imu") {
      s.type = "imu";
    } else if (type == "geometry_msgs/TwistWithCovarianceStamped" ||
               type == "geometry_msgs/TwistStamped") {
      s.type = "dvl";
    } else if (type == "waterlinked_a50_ros_driver/DVL" || type == "dvl_msgs/DVL") {
      s.type = "dvl";
      s.note = "Water Linked A50 driver messages: beam validity and figure of merit are read";
    } else if (type == "sensor_msgs/PointCloud2") {
      s.type = contains(t.topic, "sonar") || contains(t.frame_id, "sonar") ? "sonar" : "lidar";
    } else if (type == "velodyne_msgs/VelodyneScan") {
      s.type = "lidar";
    } else if (type == "sensor_msgs/Image" || type == "sensor_msgs/CompressedImage") {
      s.type = "camera";
      s.commented = true;
    } else if (type == "sensor_msgs/NavSatFix") {
      s.type = "gnss";
    } else if (type == "nav_msgs/Odometry" || type == "geometry_msgs/PoseStamped") {
      trajectories.push_back(&t);
      continue;
    } else {
      unused.push_back(&t);
      continue;
    }
    s.name = unique_name(name_from_topic(t.topic));
    sensors.push_back(s);
  }

  // Trajectory roles: by name first, then by rate (odometry the fastest, map the slowest).
  std::map<std::string, const TopicSurvey*> roles;
  std::vector<const TopicSurvey*> left;
  for (const TopicSurvey* t : trajectories) {
    const std::string& n = t->topic;
    if (!roles.count("ground_truth") &&
        (contains(n, "ground_truth") || contains(n, "groundtruth") || contains(n, "/gt")))
      roles["ground_truth"] = t;
    else if (!roles.count("map") && (contains(n, "keyframe") || contains(n, "map")))
      roles["map"] = t;
    else if (!roles.count("odometry") && contains(n, "odom"))
      roles["odometry"] = t;
    else
      left.push_back(t);
  }
  std::sort(left.begin(), left.end(),
            [](const TopicSurvey* a, const TopicSurvey* b) { return a->rate_hz > b->rate_hz; });
  if (!roles.count("odometry") && !left.empty())
    roles["odometry"] = left.front(), left.erase(left.begin());
  if (!roles.count("map") && !left.empty()) roles["map"] = left.back(), left.pop_back();
  for (const TopicSurvey* t : left) unused.push_back(t);

  // Frames: the body is what the odometry describes (Odometry.child_frame_id).
  std::string body_frame = "base_link", world_frame = "world", body_why;
  for (const char* role : {"odometry", "map", "ground_truth"}) {
    if (!roles.count(role)) continue;
    const TopicSurvey* t = roles[role];
    if (!t->child_frame.empty()) {
      body_frame = t->child_frame;
      body_why = "the child_frame_id of " + t->topic;
    }
    if (!t->frame_id.empty()) world_frame = t->frame_id;
    if (!body_why.empty()) break;
  }
  if (body_why.empty()) {
    body_why = "no Odometry names its body: confirm";
    draft.confirm.push_back("body_frame '" + body_frame + "' (no Odometry child_frame_id)");
  }

  // What stages need.
  auto has_type = [&](const char* type) {
    for (const auto& s : sensors)
      if (s.type == type && !s.commented) return true;
    return false;
  };
  if (!has_type("imu"))
    draft.missing.push_back("no IMU topic (sensor_msgs/Imu): the refine stage needs `imu`");
  if (!has_type("dvl"))
    draft.missing.push_back(
        "no DVL topic (TwistWithCovarianceStamped, TwistStamped or a Water Linked A50 driver's "
        "DVL): the refine stage's DVL/IMU factor needs `dvl` velocities");
  if (!roles.count("map") || !roles.count("odometry"))
    draft.missing.push_back(std::string("no ") + (!roles.count("map") ? "`map`" : "`odometry`") +
                            " trajectory topic (nav_msgs/Odometry or geometry_msgs/PoseStamped): "
                            "the refine and map stages need `map` and `odometry` poses");
  if (!has_type("lidar") && !has_type("sonar"))
    draft.missing.push_back(
        "no scan topic (sensor_msgs/PointCloud2 or velodyne_msgs/VelodyneScan): the map stage "
        "has nothing to map");

  Writer w;
  const std::string bag_name = survey.bag.filename().empty()
                                   ? survey.bag.parent_path().filename().string()
                                   : survey.bag.filename().string();
  std::string name = options.name.empty() ? fs::path(bag_name).stem().string() : options.name;
  for (char& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '_' && c != '-') c = '_';
  std::error_code ec;
  // Lexically: a bag linked into the folder stays where the link is.
  fs::path folder =
      fs::absolute(options.mission_folder.empty() ? fs::path(".") : options.mission_folder, ec)
          .lexically_normal();
  if (folder.filename().empty()) folder = folder.parent_path();  // "/a/b/" from "/a/b/."
  fs::path bag_rel = fs::absolute(survey.bag, ec).lexically_normal().lexically_relative(folder);
  // A bundle holds its bag: a path inside the mission folder, never absolute or above it.
  std::string bag_note;
  if (ec || bag_rel.empty() || *bag_rel.begin() == "..") {
    bag_rel = bag_name;
    bag_note =
        "  # CONFIRM: move or link " + io::display_path(survey.bag) + " into the mission folder";
    draft.confirm.push_back("bag: the bag must be inside the mission folder");
  }

  w.line("# mission.yaml drafted by `keel init` from " + io::display_path(survey.bag) + ".");
  w.line("# Read every comment marked CONFIRM; docs/mission-format.md describes each key.");
  for (const auto& m : draft.missing) w.line("# MISSING: " + m);
  w.line("keel_mission: 1");
  w.line("name: " + name);
  w.line("platform: other                 # CONFIRM: usv | hauv | other");
  w.line("body_frame: " + body_frame + "  # " + body_why);
  w.line("world_frame: " + world_frame);
  const Sensor* gnss = nullptr;
  for (const auto& s : sensors)
    if (s.type == "gnss" && s.topic->first_fix) gnss = &s;
  if (gnss) {
    const Fix& f = *gnss->topic->first_fix;
    w.line("origin:                         # CONFIRM: the first fix of " + gnss->topic->topic +
           " (world = ENU here)");
    w.line("  latitude_deg: " + num(f.latitude_deg));
    w.line("  longitude_deg: " + num(f.longitude_deg));
    w.line("  height_m: " + num(f.altitude_m) + "  # NavSatFix altitude (above the ellipsoid)");
  }
  w.line("bag: " + bag_rel.generic_string() + bag_note);
  w.line("sensors:");
  for (const Sensor& s : sensors) {
    const TopicSurvey& t = *s.topic;
    const std::string p = s.commented ? "  # " : "  ";
    const std::string q = s.commented ? "  #   " : "    ";
    if (s.commented) {
      w.line("  # CONFIRM: " + t.topic + " (" + t.type +
             (t.image ? ", " + t.image->encoding +
                            (t.image->width ? " " + std::to_string(t.image->width) + "x" +
                                                  std::to_string(t.image->height)
                                            : "")
                      : "") +
             ") needs its intrinsics (`camera:` model, size, fx fy cx cy, distortion) to be used");
      draft.confirm.push_back("camera " + t.topic + ": intrinsics");
    }
    w.line(p + "- name: " + s.name + "  # " + t.topic + " (" + t.type + ")");
    w.line(q + "type: " + s.type);
    w.line(q + "topic: " + t.topic);
    w.line(q + "rate_hz: " + nice_rate(t.rate_hz) + "  # measured " + num(t.rate_hz) + " Hz over " +
           num(t.span_s()) + " s" +
           (t.gaps ? ", " + std::to_string(t.gaps) + " gaps (longest " + num(t.max_gap_s) + " s)"
                   : ""));
    if (!s.note.empty()) w.line(q + "# " + s.note);
    // Extrinsic: body -> the message's frame, through the TF tree.
    Pose3 T_body_sensor;
    if (t.frame_id.empty()) {
      w.line(q + "# CONFIRM T_body_sensor: the messages name no frame_id");
      draft.confirm.push_back(s.name + ": T_body_sensor (no frame_id)");
    } else if (!survey.transforms.empty() &&
               io::lookup_static_transform(survey.transforms, body_frame, t.frame_id,
                                           T_body_sensor)) {
      const Eigen::Quaterniond q_bs(T_body_sensor.linear());
      const Eigen::Vector3d x = T_body_sensor.translation();
      w.line(q + "T_body_sensor: {translation: [" + num(x.x()) + ", " + num(x.y()) + ", " +
             num(x.z()) + "], rotation_xyzw: [" + num(q_bs.x()) + ", " + num(q_bs.y()) + ", " +
             num(q_bs.z()) + ", " + num(q_bs.w()) + "]}  # " + survey.transforms_topic + ": " +
             body_frame + " -> " + t.frame_id +
             (survey.transforms_topic == "/tf" ? " (CONFIRM: /tf, no /tf_static in the bag)" : ""));
    } else {
      w.line(q + "# CONFIRM T_body_sensor: no transform " + body_frame + " -> " + t.frame_id +
             (survey.transforms_topic.empty() ? " (no /tf_static in the bag)"
                                              : " in " + survey.transforms_topic));
      draft.confirm.push_back(s.name + ": T_body_sensor (" + body_frame + " -> " + t.frame_id +
                              ")");
    }
    if (t.plain_type == "sensor_msgs/PointCloud2" && t.point_time) {
      const PointTimeGuess& g = *t.point_time;
      if (g.spec) {
        const std::string mark = g.certain ? "" : "CONFIRM: ";
        w.line(q + "point_time:  # " + mark + g.evidence);
        if (g.spec->is_split())
          w.line(q + "  field: [" + g.spec->field + ", " + g.spec->nsec_field + "]");
        else
          w.line(q + "  field: " + g.spec->field + "\n" + q +
                 "  unit: " + proto::to_string(g.spec->unit));
        w.line(q + "  reference: " + proto::to_string(g.spec->reference));
        if (!g.certain) draft.confirm.push_back(s.name + ": point_time (" + g.evidence + ")");
      } else {
        w.line(q + "# " + g.evidence + ": points share the message stamp (no deskew)");
      }
    }
    if (t.plain_type == "velodyne_msgs/VelodyneScan") {
      const std::string model = t.velodyne ? velodyne_model(t.velodyne->product) : "";
      if (!model.empty()) {
        w.line(q + "packets: {model: " + model + "}  # factory byte of the first packet: " +
               velodyne_product_name(t.velodyne->product));
      } else {
        w.line(q + "packets: {model: VLP16}  # CONFIRM the model (VLP16 | VLP32C | HDL32E): " +
               (t.velodyne ? "the packets say " + velodyne_product_name(t.velodyne->product)
                           : std::string("no packet to read")));
        draft.confirm.push_back(s.name + ": packets.model");
      }
    }
  }
  if (sensors.empty()) w.line("  []  # no topic of a type Keel reads");
  if (!roles.empty()) {
    w.line("trajectories:");
    for (const char* role : {"map", "odometry", "ground_truth"}) {
      if (!roles.count(role)) continue;
      const TopicSurvey& t = *roles[role];
      std::string note = t.type + ", " + num(t.rate_hz) + " Hz";
      if (!t.child_frame.empty() && t.child_frame != body_frame)
        note += "; CONFIRM: it describes '" + t.child_frame + "', not body_frame";
      if (t.child_frame.empty()) note += "; CONFIRM: a PoseStamped of body_frame in " + t.frame_id;
      w.line("  " + std::string(role) + ": {topic: " + t.topic + "}  # " + note);
    }
  }
  if (!unused.empty()) {
    w.line("# Not used:");
    for (const TopicSurvey* t : unused)
      w.line("#   " + t->topic + " (" + t->type + ", " + std::to_string(t->messages) +
             " messages)" +
             (t->plain_type == "tf2_msgs/TFMessage" ? ": read for the extrinsics above" : ""));
  }
  draft.yaml = w.str();
  return draft;
}

}  // namespace keel::init
