#include "worker/mapping/extrinsic_refinement.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/parallel_for.h"

namespace keel::mapping {
namespace {

// Candidate points are processed in fixed blocks whose sums are added in block order, so the
// estimate does not depend on the thread count.
constexpr size_t kBlock = 4096;

struct CandidatePoint {
  Eigen::Vector3d p;  // candidate frame
  uint32_t scan;
};

struct Match {
  bool matched = false;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
};

struct Problem {
  const PlaneMap& map;
  const std::vector<CandidatePoint>& points;
  const std::vector<Eigen::Isometry3d>& T_world_reference;  // per candidate scan
  const ExtrinsicRefinementOptions& options;
};

Eigen::Vector3d to_world(const Problem& problem, const Eigen::Isometry3d& T, size_t i) {
  const CandidatePoint& c = problem.points[i];
  return problem.T_world_reference[c.scan] * (T * c.p);
}

std::vector<Match> find_matches(const Problem& problem, const Eigen::Isometry3d& T, double gate_m) {
  std::vector<Match> matches(problem.points.size());
  const double gate2 = gate_m * gate_m;
  const double reach = std::max(gate_m, problem.options.plane_extrapolation_m);
  parallel_for(problem.points.size(), problem.options.threads, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) {
      double d2 = 0.0;
      const Eigen::Vector3d p = to_world(problem, T, i);
      const uint32_t n = problem.map.nearest(p, &d2);
      const LocalPlane& plane = problem.map.plane(n);
      if (!plane.planar || d2 > reach * reach) continue;
      if (d2 > gate2 && std::abs(plane.normal.dot(p - plane.centroid)) > gate_m) continue;
      matches[i] = {true, plane.normal, plane.centroid};
    }
  });
  return matches;
}

double robust_weight(const ExtrinsicRefinementOptions& options, double r) {
  const double a = std::abs(r) / options.loss_scale_m;
  if (options.loss == RobustLoss::kCauchy) return 1.0 / (1.0 + a * a);
  return a <= 1.0 ? 1.0 : 1.0 / a;  // Huber
}

struct Normal {
  Matrix6d H = Matrix6d::Zero();
  Vector6d g = Vector6d::Zero();
  double weighted_squares = 0.0;
  size_t count = 0;
};

// J^T W J and J^T W r of the matched points at T (J w.r.t. the right perturbation).
Normal accumulate(const Problem& problem, const std::vector<Match>& matches,
                  const Eigen::Isometry3d& T) {
  const size_t blocks = (matches.size() + kBlock - 1) / kBlock;
  std::vector<Normal> partial(blocks);
  parallel_for_each(blocks, problem.options.threads, [&](size_t b) {
    Normal& out = partial[b];
    const size_t end = std::min(matches.size(), (b + 1) * kBlock);
    for (size_t i = b * kBlock; i < end; ++i) {
      const Match& match = matches[i];
      if (!match.matched) continue;
      const CandidatePoint& c = problem.points[i];
      const Eigen::Isometry3d& A = problem.T_world_reference[c.scan];
      const double r = match.normal.dot(A * (T * c.p) - match.centroid);
      // m: the plane's normal in the candidate frame; J = [m^T, (p x m)^T].
      const Eigen::Vector3d m = T.linear().transpose() * (A.linear().transpose() * match.normal);
      Vector6d J;
      J << m, c.p.cross(m);
      const double w = robust_weight(problem.options, r);
      out.H.selfadjointView<Eigen::Upper>().rankUpdate(J, w);
      out.g += w * r * J;
      out.weighted_squares += w * r * r;
      ++out.count;
    }
  });
  Normal total;
  for (const Normal& p : partial) {
    total.H += p.H;
    total.g += p.g;
    total.weighted_squares += p.weighted_squares;
    total.count += p.count;
  }
  total.H = total.H.selfadjointView<Eigen::Upper>();
  return total;
}

ResidualSummary summarize(const Problem& problem, const Eigen::Isometry3d& T) {
  const double gate = problem.options.final_correspondence_m;
  const std::vector<Match> matches = find_matches(problem, T, gate);
  std::vector<double> r;
  for (size_t i = 0; i < matches.size(); ++i)
    if (matches[i].matched)
      r.push_back(std::abs(matches[i].normal.dot(to_world(problem, T, i) - matches[i].centroid)));
  ResidualSummary s;
  s.points = problem.points.size();
  s.matched = r.size();
  const int bins = std::max(1, problem.options.histogram_bins);
  for (int b = 0; b <= bins; ++b) s.histogram_edges_m.push_back(gate * b / bins);
  s.histogram_counts.assign(bins, 0);
  if (r.empty()) return s;
  double squares = 0.0;
  for (double v : r) {
    squares += v * v;
    ++s.histogram_counts[std::min<size_t>(bins - 1, static_cast<size_t>(v / gate * bins))];
  }
  s.rms_m = std::sqrt(squares / r.size());
  std::sort(r.begin(), r.end());
  auto quantile = [&](double q) {
    const double x = q * (r.size() - 1);
    const size_t lo = static_cast<size_t>(x);
    const size_t hi = std::min(lo + 1, r.size() - 1);
    return r[lo] + (x - lo) * (r[hi] - r[lo]);
  };
  s.median_m = quantile(0.5);
  s.p90_m = quantile(0.9);
  return s;
}

void check_options(const ExtrinsicRefinementOptions& o) {
  if (!(o.loss_scale_m > 0) || !(o.final_correspondence_m > 0) ||
      o.max_correspondence_m < o.final_correspondence_m || o.max_iterations < 1 ||
      o.gauss_newton_steps < 1 || !(o.unobservable_ratio > 0 && o.unobservable_ratio < 1))
    throw std::invalid_argument(
        "refine_extrinsic: needs loss_scale_m > 0, 0 < final_correspondence_m <= "
        "max_correspondence_m, iterations >= 1 and 0 < unobservable_ratio < 1");
}

std::string percent(double fraction) {
  std::ostringstream out;
  out << fraction * 100.0 << " %";
  return out.str();
}

}  // namespace

Eigen::Isometry3d apply_right_perturbation(const Eigen::Isometry3d& T, const Vector6d& delta) {
  Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
  const Eigen::Vector3d phi = delta.tail<3>();
  const double angle = phi.norm();
  if (angle > 0) step.linear() = Eigen::AngleAxisd(angle, phi / angle).toRotationMatrix();
  step.translation() = delta.head<3>();
  Eigen::Isometry3d out = T * step;
  // Re-orthonormalise so thousands of steps cannot drift off SO(3).
  out.linear() = Eigen::Quaterniond(out.linear()).normalized().toRotationMatrix();
  return out;
}

std::vector<Eigen::Vector3f> reference_map_points(const std::vector<PlacedScan>& reference_scans,
                                                  const Eigen::Isometry3d& T_body_reference) {
  std::vector<Eigen::Vector3f> out;
  for (const PlacedScan& scan : reference_scans) {
    const Eigen::Isometry3d T_world_reference = scan.T_world_body * T_body_reference;
    for (const Eigen::Vector3f& p : scan.points)
      out.push_back((T_world_reference * p.cast<double>()).cast<float>());
  }
  return out;
}

ExtrinsicRefinementResult refine_extrinsic(const std::vector<PlacedScan>& reference_scans,
                                           const std::vector<PlacedScan>& candidate_scans,
                                           const Eigen::Isometry3d& T_body_reference,
                                           const Eigen::Isometry3d& T_reference_candidate_initial,
                                           const std::string& reference_name,
                                           const std::string& candidate_name,
                                           const ExtrinsicRefinementOptions& options) {
  check_options(options);
  const std::vector<Eigen::Vector3f> points =
      reference_map_points(reference_scans, T_body_reference);
  if (points.empty())
    throw std::invalid_argument("refine_extrinsic: reference '" + reference_name +
                                "' has no points");
  const PlaneMap map(points, options.planes);
  return refine_extrinsic(map, candidate_scans, T_body_reference, T_reference_candidate_initial,
                          reference_name, candidate_name, options);
}

ExtrinsicRefinementResult refine_extrinsic(const PlaneMap& map,
                                           const std::vector<PlacedScan>& candidate_scans,
                                           const Eigen::Isometry3d& T_body_reference,
                                           const Eigen::Isometry3d& T_reference_candidate_initial,
                                           const std::string& reference_name,
                                           const std::string& candidate_name,
                                           const ExtrinsicRefinementOptions& options) {
  check_options(options);
  ExtrinsicRefinementResult result;
  result.T_reference_candidate = T_reference_candidate_initial;
  result.reference_points = map.size();
  result.reference_planar = map.planar_count();

  // 2. The candidate points (strided down to max_candidate_points) and their scans' placement.
  size_t total = 0;
  for (const PlacedScan& scan : candidate_scans) total += scan.points.size();
  const size_t stride =
      options.max_candidate_points > 0 && total > options.max_candidate_points
          ? (total + options.max_candidate_points - 1) / options.max_candidate_points
          : 1;
  std::vector<CandidatePoint> points;
  std::vector<Eigen::Isometry3d> T_world_reference;
  size_t k = 0;
  double squared_range = 0.0;
  for (const PlacedScan& scan : candidate_scans) {
    T_world_reference.push_back(scan.T_world_body * T_body_reference);
    for (const Eigen::Vector3f& p : scan.points)
      if (k++ % stride == 0) {
        points.push_back({p.cast<double>(), static_cast<uint32_t>(T_world_reference.size() - 1)});
        squared_range += p.cast<double>().squaredNorm();
      }
  }
  const Problem problem{map, points, T_world_reference, options};
  result.before = summarize(problem, T_reference_candidate_initial);

  // 3. Overlap: enough candidate points near a planar part of the reference map at the widest
  // gate, or the candidate is refused.
  const std::vector<Match> initial =
      find_matches(problem, T_reference_candidate_initial, options.max_correspondence_m);
  const size_t overlap =
      std::count_if(initial.begin(), initial.end(), [](const Match& m) { return m.matched; });
  if (points.empty() || overlap < options.min_overlap_points ||
      overlap < options.min_overlap_fraction * points.size()) {
    std::ostringstream reason;
    reason << "no overlap between candidate '" << candidate_name << "' and reference '"
           << reference_name << "': " << overlap << " of " << points.size() << " " << candidate_name
           << " points lie within " << options.max_correspondence_m << " m of a planar part of "
           << reference_name << "'s map (needs at least " << options.min_overlap_points << " and "
           << percent(options.min_overlap_fraction) << ")";
    result.refused = true;
    result.reason = reason.str();
    result.after = result.before;
    return result;
  }

  // 4. ICP: correspondences at a shrinking gate, then IRLS Gauss-Newton steps solved in the
  // observable subspace of the scaled information.
  const double L = std::max(1e-3, std::sqrt(squared_range / points.size()));
  result.rotation_scale_m = L;
  Vector6d unscale;  // S^-1: tangent = S^-1 * scaled
  unscale << 1, 1, 1, 1 / L, 1 / L, 1 / L;
  auto decompose = [&](const Matrix6d& H) {
    const Matrix6d H_scaled = unscale.asDiagonal() * H * unscale.asDiagonal();
    return Eigen::SelfAdjointEigenSolver<Matrix6d>(H_scaled);
  };
  Eigen::Isometry3d T = T_reference_candidate_initial;
  for (int iteration = 0; iteration < options.max_iterations; ++iteration) {
    result.iterations = iteration + 1;
    const double gate = std::max(options.final_correspondence_m,
                                 options.max_correspondence_m * std::pow(0.5, iteration));
    const std::vector<Match> matches = find_matches(problem, T, gate);
    bool first_step_small = false;
    for (int step = 0; step < options.gauss_newton_steps; ++step) {
      const Normal normal = accumulate(problem, matches, T);
      if (normal.count < 6) break;
      const auto eig = decompose(normal.H);
      const Vector6d g_scaled = unscale.asDiagonal() * normal.g;
      const double largest = eig.eigenvalues()(5);
      Vector6d delta_scaled = Vector6d::Zero();
      for (int j = 0; j < 6; ++j) {
        const double lambda = eig.eigenvalues()(j);
        if (lambda < options.unobservable_ratio * largest) continue;
        const Vector6d v = eig.eigenvectors().col(j);
        delta_scaled -= v * (v.dot(g_scaled) / lambda);
      }
      const Vector6d delta = unscale.asDiagonal() * delta_scaled;
      T = apply_right_perturbation(T, delta);
      const bool small = delta.head<3>().norm() < options.converged_translation_m &&
                         delta.tail<3>().norm() < options.converged_rotation_rad;
      if (step == 0) first_step_small = small;
      if (small) break;
    }
    if (gate <= options.final_correspondence_m && first_step_small) {
      result.converged = true;
      break;
    }
  }
  result.T_reference_candidate = T;
  result.after = summarize(problem, T);

  // 5. Covariance and observability at the estimate.
  const std::vector<Match> matches = find_matches(problem, T, options.final_correspondence_m);
  const Normal normal = accumulate(problem, matches, T);
  if (normal.count > 6) {
    const auto eig = decompose(normal.H);
    const double largest = std::max(eig.eigenvalues()(5), 1e-300);
    result.residual_sigma_m = std::sqrt(normal.weighted_squares / (normal.count - 6));
    Matrix6d H_scaled_inverse = Matrix6d::Zero();
    for (int j = 0; j < 6; ++j) {
      const double lambda = eig.eigenvalues()(j);
      const Vector6d v = eig.eigenvectors().col(j);
      H_scaled_inverse += v * v.transpose() / std::max(lambda, largest * 1e-15);
      Vector6d u = unscale.asDiagonal() * v;
      u.normalize();
      if (u.cwiseAbs().maxCoeff() == -u.minCoeff()) u = -u;  // largest component positive
      result.information_eigenvalues(j) = lambda;
      result.information_eigenvectors.col(j) = u;
      if (lambda < options.unobservable_ratio * largest)
        result.unobservable.push_back({u, lambda, lambda / largest});
    }
    result.covariance = result.residual_sigma_m * result.residual_sigma_m *
                        (unscale.asDiagonal() * H_scaled_inverse * unscale.asDiagonal());
  }
  return result;
}

}  // namespace keel::mapping
