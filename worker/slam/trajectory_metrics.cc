#include "worker/slam/trajectory_metrics.h"

#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "worker/slam/so3.h"

namespace keel::slam {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

double rotation_angle_deg(const Eigen::Matrix3d& R) { return so3_log(R).norm() * kRadToDeg; }

SimilarityTransform align(const std::vector<Pose3>& reference, const std::vector<Pose3>& estimate,
                          Alignment alignment) {
  if (alignment == Alignment::kNone) return {};
  std::vector<Eigen::Vector3d> x, y;
  x.reserve(estimate.size());
  y.reserve(reference.size());
  for (size_t k = 0; k < estimate.size(); ++k) {
    x.push_back(estimate[k].translation());
    y.push_back(reference[k].translation());
  }
  return umeyama_alignment(x, y, alignment == Alignment::kSim3);
}

void check_same_size(size_t a, size_t b, const char* what) {
  if (a != b) {
    throw std::invalid_argument(std::string(what) + ": reference has " + std::to_string(a) +
                                " poses, estimate " + std::to_string(b) + "; expected equal");
  }
  if (a == 0) throw std::invalid_argument(std::string(what) + ": no poses");
}

std::vector<std::pair<size_t, size_t>> frame_pairs(size_t n, size_t d, bool all_pairs) {
  std::vector<std::pair<size_t, size_t>> pairs;
  if (all_pairs) {
    for (size_t i = 0; i + d < n; ++i) pairs.emplace_back(i, i + d);
  } else {
    for (size_t i = 0; i + d < n; i += d) pairs.emplace_back(i, i + d);
  }
  return pairs;
}

std::vector<std::pair<size_t, size_t>> path_pairs(const std::vector<Pose3>& poses, double delta,
                                                  double tolerance, bool all_pairs) {
  std::vector<double> path(poses.size(), 0.0);  // cumulative arc length
  for (size_t k = 1; k < poses.size(); ++k) {
    path[k] = path[k - 1] + (poses[k].translation() - poses[k - 1].translation()).norm();
  }
  std::vector<std::pair<size_t, size_t>> pairs;
  if (all_pairs) {
    for (size_t i = 0; i < poses.size(); ++i) {
      const double target = path[i] + delta;
      const size_t hi = static_cast<size_t>(
          std::lower_bound(path.begin() + static_cast<std::ptrdiff_t>(i), path.end(), target) -
          path.begin());
      size_t best = poses.size();
      for (size_t j : {hi, hi - 1}) {  // the first index at or past the target, and the one before
        if (j <= i || j >= poses.size()) continue;
        if (best == poses.size() || std::abs(path[j] - target) < std::abs(path[best] - target)) {
          best = j;
        }
      }
      if (best < poses.size() && std::abs(path[best] - target) <= tolerance) {
        pairs.emplace_back(i, best);
      }
    }
  } else {
    // evo filter_pairs_by_path: an index is kept each time the path since the last kept one
    // reaches delta; consecutive kept indices form the pairs.
    std::vector<size_t> ids;
    double since = 0.0;
    for (size_t k = 1; k < poses.size(); ++k) {
      since += path[k] - path[k - 1];
      if (since >= delta) {
        ids.push_back(k);
        since = 0.0;
      }
    }
    for (size_t k = 1; k < ids.size(); ++k) pairs.emplace_back(ids[k - 1], ids[k]);
  }
  return pairs;
}

}  // namespace

Pose3 SimilarityTransform::apply(const Pose3& T) const {
  Pose3 out = Pose3::Identity();
  out.linear() = R * T.linear();
  out.translation() = scale * R * T.translation() + t;
  return out;
}

SimilarityTransform umeyama_alignment(const std::vector<Eigen::Vector3d>& x,
                                      const std::vector<Eigen::Vector3d>& y, bool with_scale) {
  if (x.size() != y.size()) {
    throw std::invalid_argument("umeyama_alignment: " + std::to_string(x.size()) + " vs " +
                                std::to_string(y.size()) + " points; expected equal counts");
  }
  if (x.size() < 3) throw std::invalid_argument("umeyama_alignment: needs at least 3 points");
  const double n = static_cast<double>(x.size());
  Eigen::Vector3d mx = Eigen::Vector3d::Zero(), my = Eigen::Vector3d::Zero();
  for (size_t k = 0; k < x.size(); ++k) {
    mx += x[k];
    my += y[k];
  }
  mx /= n;
  my /= n;
  Eigen::Matrix3d sigma = Eigen::Matrix3d::Zero();  // Umeyama Eq. (38)
  double var_x = 0.0;                               // Eq. (36)
  for (size_t k = 0; k < x.size(); ++k) {
    sigma += (y[k] - my) * (x[k] - mx).transpose();
    var_x += (x[k] - mx).squaredNorm();
  }
  sigma /= n;
  var_x /= n;
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(sigma, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Vector3d d = svd.singularValues();
  if (var_x <= 0.0 || d(1) <= 1e-12 * std::max(1.0, d(0))) {
    throw std::invalid_argument(
        "umeyama_alignment: degenerate point sets (coincident or collinear)");
  }
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();  // Eq. (39)
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0.0) S(2, 2) = -1.0;
  SimilarityTransform out;
  out.R = svd.matrixU() * S * svd.matrixV().transpose();                // Eq. (40)
  out.scale = with_scale ? (d.asDiagonal() * S).trace() / var_x : 1.0;  // Eq. (42)
  out.t = my - out.scale * out.R * mx;                                  // Eq. (41)
  return out;
}

ErrorStatistics error_statistics(std::vector<double> errors) {
  ErrorStatistics s;
  s.count = errors.size();
  if (errors.empty()) return s;
  const double n = static_cast<double>(errors.size());
  double sum = 0.0, sum_sq = 0.0;
  for (double e : errors) {
    sum += e;
    sum_sq += e * e;
  }
  s.mean = sum / n;
  s.rmse = std::sqrt(sum_sq / n);
  double var = 0.0;
  for (double e : errors) var += (e - s.mean) * (e - s.mean);
  s.std = std::sqrt(var / n);
  std::sort(errors.begin(), errors.end());
  s.min = errors.front();
  s.max = errors.back();
  const size_t m = errors.size() / 2;
  s.median = errors.size() % 2 == 1 ? errors[m] : 0.5 * (errors[m - 1] + errors[m]);
  return s;
}

Association associate_by_time(const Trajectory& reference, const Trajectory& estimate,
                              const AssociationOptions& options) {
  const bool ref_shorter = reference.size() <= estimate.size();
  const Trajectory& shorter = ref_shorter ? reference : estimate;
  const Trajectory& longer = ref_shorter ? estimate : reference;
  // Stamps in seconds relative to a common origin; the estimate carries the offset.
  const TimeNs origin = std::min(reference.empty() ? 0 : reference.front().t_ns,
                                 estimate.empty() ? 0 : estimate.front().t_ns);
  const double offset_longer = ref_shorter ? options.time_offset_s : 0.0;
  const double offset_shorter = ref_shorter ? 0.0 : options.time_offset_s;
  std::vector<double> t_long(longer.size());
  for (size_t k = 0; k < longer.size(); ++k) {
    t_long[k] = ns_to_seconds(longer[k].t_ns - origin) + offset_longer;
  }
  Association a;
  for (size_t i = 0; i < shorter.size() && !t_long.empty(); ++i) {
    const double t = ns_to_seconds(shorter[i].t_ns - origin) + offset_shorter;
    auto it = std::lower_bound(t_long.begin(), t_long.end(), t);
    size_t best = it == t_long.end() ? t_long.size() - 1 : static_cast<size_t>(it - t_long.begin());
    if (best > 0 && std::abs(t_long[best - 1] - t) <= std::abs(t_long[best] - t)) --best;
    if (std::abs(t_long[best] - t) <= options.max_difference_s) {
      (ref_shorter ? a.reference_index : a.estimate_index).push_back(i);
      (ref_shorter ? a.estimate_index : a.reference_index).push_back(best);
    }
  }
  return a;
}

AteResult absolute_trajectory_error(const std::vector<Pose3>& reference,
                                    const std::vector<Pose3>& estimate, Alignment alignment) {
  check_same_size(reference.size(), estimate.size(), "absolute_trajectory_error");
  AteResult r;
  r.alignment = align(reference, estimate, alignment);
  std::vector<double> rot;
  r.translation_errors_m.reserve(estimate.size());
  rot.reserve(estimate.size());
  for (size_t k = 0; k < estimate.size(); ++k) {
    const Pose3 est = r.alignment.apply(estimate[k]);
    r.translation_errors_m.push_back((est.translation() - reference[k].translation()).norm());
    rot.push_back(rotation_angle_deg(reference[k].linear().transpose() * est.linear()));
  }
  r.translation_m = error_statistics(r.translation_errors_m);
  r.rotation_deg = error_statistics(rot);
  return r;
}

namespace {
void associated_poses(const Trajectory& reference, const Trajectory& estimate,
                      const AssociationOptions& options, std::vector<Pose3>* ref,
                      std::vector<Pose3>* est) {
  const Association a = associate_by_time(reference, estimate, options);
  if (a.reference_index.empty()) {
    throw std::invalid_argument(
        "no matching timestamps between the reference and the estimate "
        "within " +
        std::to_string(options.max_difference_s) + " s");
  }
  for (size_t k = 0; k < a.reference_index.size(); ++k) {
    ref->push_back(reference[a.reference_index[k]].T_world_body);
    est->push_back(estimate[a.estimate_index[k]].T_world_body);
  }
}
}  // namespace

AteResult absolute_trajectory_error(const Trajectory& reference, const Trajectory& estimate,
                                    Alignment alignment, const AssociationOptions& options) {
  std::vector<Pose3> ref, est;
  associated_poses(reference, estimate, options, &ref, &est);
  return absolute_trajectory_error(ref, est, alignment);
}

RpeResult relative_pose_error(const std::vector<Pose3>& reference,
                              const std::vector<Pose3>& estimate, const RpeOptions& options) {
  check_same_size(reference.size(), estimate.size(), "relative_pose_error");
  if (!(options.delta > 0.0)) throw std::invalid_argument("relative_pose_error: delta must be > 0");
  const SimilarityTransform S = align(reference, estimate, options.alignment);
  RpeResult r;
  if (options.unit == DeltaUnit::kFrames) {
    const size_t d = static_cast<size_t>(std::llround(options.delta));
    if (d == 0 || std::abs(options.delta - static_cast<double>(d)) > 1e-9) {
      throw std::invalid_argument("relative_pose_error: a frame delta must be a positive integer");
    }
    r.pairs = frame_pairs(reference.size(), d, options.all_pairs);
  } else {
    std::vector<Pose3> aligned;
    if (!options.pairs_from_reference) {
      for (const Pose3& T : estimate) aligned.push_back(S.apply(T));
    }
    r.pairs = path_pairs(options.pairs_from_reference ? reference : aligned, options.delta,
                         options.delta * options.rel_tolerance, options.all_pairs);
  }
  if (r.pairs.empty()) {
    throw std::invalid_argument("relative_pose_error: delta " + std::to_string(options.delta) +
                                " gives no pose pairs");
  }
  std::vector<double> trans, rot;
  for (const auto& [i, j] : r.pairs) {
    const Pose3 d_ref = reference[i].inverse() * reference[j];
    const Pose3 d_est = S.apply(estimate[i]).inverse() * S.apply(estimate[j]);
    const Pose3 E = d_ref.inverse() * d_est;
    trans.push_back(E.translation().norm());
    rot.push_back(rotation_angle_deg(E.linear()));
  }
  r.translation_m = error_statistics(trans);
  r.rotation_deg = error_statistics(rot);
  return r;
}

RpeResult relative_pose_error(const Trajectory& reference, const Trajectory& estimate,
                              const RpeOptions& options, const AssociationOptions& association) {
  std::vector<Pose3> ref, est;
  associated_poses(reference, estimate, association, &ref, &est);
  return relative_pose_error(ref, est, options);
}

}  // namespace keel::slam
