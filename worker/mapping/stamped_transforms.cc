#include "worker/mapping/stamped_transforms.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace keel::mapping {
namespace {

std::string describe_sample(const std::string& name, size_t i, TimeNs t_ns) {
  std::ostringstream out;
  out << name << " sample " << i << " (t=" << format_seconds(t_ns) << " s)";
  return out.str();
}

void check_rotation(const Eigen::Matrix3d& R, const std::string& where) {
  if (!R.allFinite()) throw std::invalid_argument(where + ": rotation is not finite");
  const double orthogonality_error = (R.transpose() * R - Eigen::Matrix3d::Identity()).norm();
  if (orthogonality_error > 1e-6 || R.determinant() < 0.0) {
    throw std::invalid_argument(where +
                                ": rotation is not a proper rotation matrix (|R^T R - I| = " +
                                std::to_string(orthogonality_error) + ")");
  }
}

}  // namespace

Pose3 interpolate_pose(const Pose3& T_a, const Pose3& T_b, double s) {
  const Eigen::Quaterniond q_a(T_a.linear());
  const Eigen::Quaterniond q_b(T_b.linear());
  // Eigen's slerp takes the shorter arc (it flips q_b when q_a . q_b < 0).
  return make_pose(q_a.slerp(s, q_b), (1.0 - s) * T_a.translation() + s * T_b.translation());
}

StampedTransforms::StampedTransforms(const Trajectory& samples, std::string name)
    : name_(std::move(name)) {
  if (samples.empty()) throw std::invalid_argument(name_ + ": no poses");
  stamps_.reserve(samples.size());
  rotations_.reserve(samples.size());
  translations_.reserve(samples.size());
  for (size_t i = 0; i < samples.size(); ++i) {
    const StampedPose& sample = samples[i];
    if (i > 0 && sample.t_ns <= samples[i - 1].t_ns) {
      throw std::invalid_argument(describe_sample(name_, i, sample.t_ns) +
                                  ": stamps must be strictly increasing (previous t=" +
                                  format_seconds(samples[i - 1].t_ns) + " s)");
    }
    const std::string where = describe_sample(name_, i, sample.t_ns);
    check_rotation(sample.T_world_body.linear(), where);
    if (!sample.T_world_body.translation().allFinite()) {
      throw std::invalid_argument(where + ": translation is not finite");
    }
    stamps_.push_back(sample.t_ns);
    rotations_.emplace_back(Eigen::Quaterniond(sample.T_world_body.linear()).normalized());
    translations_.push_back(sample.T_world_body.translation());
  }
}

Pose3 StampedTransforms::sample(size_t i) const {
  return make_pose(rotations_.at(i), translations_.at(i));
}

Pose3 StampedTransforms::at(TimeNs t_ns) const {
  if (!covers(t_ns)) {
    throw std::out_of_range(name_ + ": no pose at t=" + format_seconds(t_ns) +
                            " s, outside the covered span [" + format_seconds(begin_ns()) + ", " +
                            format_seconds(end_ns()) + "] s (poses are not extrapolated)");
  }
  return interpolate_inside(t_ns);
}

Pose3 StampedTransforms::at_clamped(TimeNs t_ns) const {
  return interpolate_inside(std::clamp(t_ns, begin_ns(), end_ns()));
}

Pose3 StampedTransforms::interpolate_inside(TimeNs t_ns) const {
  // First stamp strictly after t: the bracket is [upper - 1, upper].
  const auto upper = std::upper_bound(stamps_.begin(), stamps_.end(), t_ns);
  if (upper == stamps_.end()) return sample(stamps_.size() - 1);  // t == last stamp
  const size_t i1 = static_cast<size_t>(upper - stamps_.begin());
  const size_t i0 = i1 - 1;
  // Integer differences first: exact for any mission length.
  const double s =
      static_cast<double>(t_ns - stamps_[i0]) / static_cast<double>(stamps_[i1] - stamps_[i0]);
  return make_pose(rotations_[i0].slerp(s, rotations_[i1]),
                   (1.0 - s) * translations_[i0] + s * translations_[i1]);
}

}  // namespace keel::mapping
