#include "worker/main/trajectory_source.h"

#include <cmath>
#include <stdexcept>

#include "worker/io/bag/bag_reader.h"
#include "worker/io/text_lines.h"
#include "worker/io/tum.h"

namespace keel::worker {

namespace fs = std::filesystem;

TrajectoryFormat trajectory_format_from_string(const std::string& text) {
  if (text == "tum") return TrajectoryFormat::kTum;
  if (text == "kitti") return TrajectoryFormat::kKitti;
  throw std::invalid_argument("--format " + text + ": expected tum or kitti");
}

Trajectory read_kitti_poses(const fs::path& path) {
  io::TextLines lines(path);
  Trajectory trajectory;
  std::string_view line;
  while (lines.next(line)) {
    std::string_view rest = io::trim(line);
    if (rest.empty() || rest.front() == '#') continue;
    double v[12];
    size_t count = 0;
    while (!rest.empty()) {
      const size_t end = rest.find_first_of(" \t");
      const std::string_view token = rest.substr(0, end);
      if (count < 12 && (!io::parse_double(token, v[count]) || !std::isfinite(v[count])))
        lines.fail("value " + std::to_string(count + 1) + ": expected a finite number, got '" +
                   std::string(token) + "'");
      ++count;
      rest = end == std::string_view::npos ? std::string_view() : io::trim(rest.substr(end));
    }
    if (count != 12)
      lines.fail("expected 12 values (row-major 3x4 pose), found " + std::to_string(count));
    Eigen::Matrix3d R;
    R << v[0], v[1], v[2], v[4], v[5], v[6], v[8], v[9], v[10];
    const double orthogonality = (R.transpose() * R - Eigen::Matrix3d::Identity()).norm();
    if (orthogonality > 1e-2 || R.determinant() <= 0.0)
      lines.fail(
          "rotation block is not a rotation (|R^T R - I| = " + std::to_string(orthogonality) +
          ", det = " + std::to_string(R.determinant()) + ")");
    StampedPose pose;
    pose.t_ns = static_cast<TimeNs>(trajectory.size()) * 1000000000LL;
    // Rounded to the nearest rotation (files carry 9 digits); translations are kept as given.
    pose.T_world_body = make_pose(Eigen::Quaterniond(R), Eigen::Vector3d(v[3], v[7], v[11]));
    trajectory.push_back(pose);
  }
  return trajectory;
}

LoadedTrajectory load_trajectory_argument(const std::string& spec, TrajectoryFormat format) {
  std::error_code ec;
  LoadedTrajectory out;
  if (fs::is_regular_file(spec, ec)) {
    out.source = spec;
    out.poses = format == TrajectoryFormat::kKitti ? read_kitti_poses(spec) : io::read_tum(spec);
  } else {
    const size_t split = spec.find(".bag:");
    if (split == std::string::npos)
      throw std::invalid_argument(spec + ": no such file (a bag topic is written BAG:TOPIC)");
    const fs::path bag_path = spec.substr(0, split + 4);
    const std::string topic = spec.substr(split + 5);
    if (topic.empty()) throw std::invalid_argument(spec + ": expected a topic after the ':'");
    if (!fs::is_regular_file(bag_path, ec))
      throw std::invalid_argument(bag_path.string() + ": no such bag");
    io::BagReader bag(bag_path);
    out.source = "topic " + topic + " of " + bag_path.string();
    out.poses = bag.read_trajectory(topic);
  }
  if (out.poses.empty()) throw std::invalid_argument(out.source + ": no poses");
  return out;
}

}  // namespace keel::worker
