#include "worker/io/tum.h"

#include <cmath>

#include "worker/io/text_lines.h"
#include "worker/io/text_writer.h"

namespace keel::io {

namespace {

// Splits on spaces and tabs into at most `max` tokens; returns the token count found.
size_t split_spaces(std::string_view line, std::string_view* tokens, size_t max) {
  size_t count = 0, i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    if (i >= line.size()) break;
    const size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
    if (count < max) tokens[count] = line.substr(start, i - start);
    ++count;
  }
  return count;
}

constexpr const char* kColumns[8] = {"t", "x", "y", "z", "qx", "qy", "qz", "qw"};

}  // namespace

Trajectory read_tum(const std::filesystem::path& path) {
  TextLines lines(path);
  Trajectory trajectory;
  std::string_view line;
  std::string_view tokens[8];
  while (lines.next(line)) {
    const std::string_view content = trim(line);
    if (content.empty() || content.front() == '#') continue;
    const size_t n = split_spaces(content, tokens, 8);
    if (n != 8) lines.fail("expected 8 values 't x y z qx qy qz qw', found " + std::to_string(n));
    StampedPose pose;
    try {
      pose.t_ns = parse_seconds_exact(tokens[0]);
    } catch (const std::exception&) {
      lines.fail("t: expected time in decimal seconds, got '" + std::string(tokens[0]) + "'");
    }
    double v[8];
    for (int i = 1; i < 8; ++i) {
      if (!parse_double(tokens[i], v[i]) || !std::isfinite(v[i]))
        lines.fail(std::string(kColumns[i]) + ": expected a finite number, got '" +
                   std::string(tokens[i]) + "'");
    }
    const Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
    if (std::abs(q.norm() - 1.0) > 1e-3)
      lines.fail("quaternion: expected unit norm, |q| = " + std::to_string(q.norm()));
    if (!trajectory.empty() && pose.t_ns <= trajectory.back().t_ns)
      lines.fail(std::string(pose.t_ns == trajectory.back().t_ns ? "duplicate" : "decreasing") +
                 " timestamp " + format_seconds(pose.t_ns) + " (previous pose " +
                 format_seconds(trajectory.back().t_ns) + "); expected strictly increasing time");
    pose.T_world_body = make_pose(q, Eigen::Vector3d(v[1], v[2], v[3]));
    trajectory.push_back(pose);
  }
  return trajectory;
}

void write_tum(const std::filesystem::path& path, const Trajectory& trajectory) {
  TextWriter w(path);
  w.text("# t x y z qx qy qz qw\n");
  for (const auto& pose : trajectory) {
    const Eigen::Vector3d t = pose.T_world_body.translation();
    const Eigen::Quaterniond q(pose.T_world_body.rotation());
    w.seconds(pose.t_ns);
    for (double x : {t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()}) w.text(" ").number(x);
    w.text("\n");
  }
  w.close();
}

}  // namespace keel::io
