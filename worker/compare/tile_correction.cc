#include "worker/compare/tile_correction.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <optional>

#include "core/robust_spread.h"
#include "worker/compare/nearest_index.h"

namespace keel::compare {
namespace {

using Vector6 = Eigen::Matrix<double, 6, 1>;
using Matrix6 = Eigen::Matrix<double, 6, 6>;

std::vector<Eigen::Vector3f> positions(const std::vector<CoreSample>& cores) {
  std::vector<Eigen::Vector3f> out(cores.size());
  for (size_t i = 0; i < cores.size(); ++i) out[i] = cores[i].position_m.cast<float>();
  return out;
}

std::vector<char> stable_in(const std::vector<CoreSample>& cores, const NearestIndex& index,
                            const std::vector<double>& residual, double band, double radius) {
  std::vector<char> stable(cores.size(), 1);
  std::vector<uint32_t> near;
  for (size_t i = 0; i < cores.size(); ++i) {
    if (std::abs(residual[i]) <= band) continue;
    index.within(cores[i].position_m.cast<float>(), radius, &near);
    for (uint32_t j : near) stable[j] = 0;
    stable[i] = 0;
  }
  return stable;
}

struct Frame {
  Eigen::Vector3d center;
  double length;
  Vector6 jacobian(const CoreSample& c) const {
    Vector6 J;
    J.head<3>() = (c.position_m - center).cross(c.normal) / length;
    J.tail<3>() = c.normal;
    return J;
  }
};

struct Candidate {
  Vector6 x = Vector6::Zero();
  size_t stable = 0;
  std::vector<std::string> fixed;
};

const char* kDirectionNames[6] = {"rx", "ry", "rz", "tx", "ty", "tz"};

// Huber-weighted least squares of d + J x on the stable cores, solved along H's constrained
// eigenvectors only. False when no direction is constrained.
bool solve(const std::vector<CoreSample>& cores, const Frame& frame,
           const std::vector<char>& stable, const std::vector<double>& residual, double noise,
           const TileCorrectionOptions& o, Vector6* x, std::vector<std::string>* fixed) {
  Matrix6 H = Matrix6::Zero();
  Vector6 g = Vector6::Zero();
  const double k = o.huber_k * noise;
  for (size_t i = 0; i < cores.size(); ++i) {
    if (!stable[i]) continue;
    const double r = std::abs(residual[i]);
    const double w = r <= k ? 1.0 : k / r;
    const Vector6 J = frame.jacobian(cores[i]);
    H += w * J * J.transpose();
    g += w * J * cores[i].distance_m;
  }
  const Eigen::SelfAdjointEigenSolver<Matrix6> eig(H);
  const double floor = o.min_eigenvalue_fraction * H.trace() / 6.0;
  Vector6 solution = Vector6::Zero();
  fixed->clear();
  for (int e = 0; e < 6; ++e) {
    const double lambda = eig.eigenvalues()[e];
    if (!(lambda > floor) || lambda <= 0.0) continue;
    const Vector6 v = eig.eigenvectors().col(e);
    solution -= v * (v.dot(g) / lambda);
    int largest = 0;
    v.cwiseAbs().maxCoeff(&largest);
    fixed->push_back(kDirectionNames[largest]);
  }
  std::sort(fixed->begin(), fixed->end());
  *x = solution;
  return !fixed->empty();
}

// Alternates the stable set and the correction from `start` until the set settles.
std::optional<Candidate> refine(const std::vector<CoreSample>& cores, const NearestIndex& index,
                                const Frame& frame, Vector6 x, double noise, double band,
                                const TileCorrectionOptions& o) {
  std::vector<double> residual(cores.size());
  std::vector<char> stable, previous;
  Candidate out;
  for (int round = 0; round < o.max_rounds; ++round) {
    for (size_t i = 0; i < cores.size(); ++i)
      residual[i] = cores[i].distance_m + frame.jacobian(cores[i]).dot(x);
    stable = stable_in(cores, index, residual, band, o.leave_out_radius_m);
    const size_t count = size_t(std::count(stable.begin(), stable.end(), 1));
    if (count < o.min_stable_cores) return std::nullopt;
    if (stable == previous) break;
    previous = stable;
    if (!solve(cores, frame, stable, residual, noise, o, &x, &out.fixed)) return std::nullopt;
  }
  out.x = x;
  for (size_t i = 0; i < cores.size(); ++i)
    residual[i] = cores[i].distance_m + frame.jacobian(cores[i]).dot(x);
  stable = stable_in(cores, index, residual, band, o.leave_out_radius_m);
  out.stable = size_t(std::count(stable.begin(), stable.end(), 1));
  return out;
}

// The offset most cores share: Huber least squares over all cores, its scale the MAD of d
// about its median (an offset moves the median, not the spread about it).
Vector6 dominant_offset(const std::vector<CoreSample>& cores, const Frame& frame,
                        const TileCorrectionOptions& o) {
  std::vector<double> d(cores.size());
  for (size_t i = 0; i < cores.size(); ++i) d[i] = cores[i].distance_m;
  const RobustSpread spread = robust_spread(d);
  const std::vector<char> all(cores.size(), 1);
  std::vector<double> residual(cores.size());
  Vector6 x = Vector6::Zero();
  std::vector<std::string> fixed;
  for (int round = 0; round < o.max_rounds; ++round) {
    for (size_t i = 0; i < cores.size(); ++i)
      residual[i] = cores[i].distance_m + frame.jacobian(cores[i]).dot(x);
    if (!solve(cores, frame, all, residual, std::max(spread.sigma, 1e-6), o, &x, &fixed)) break;
  }
  return x;
}

}  // namespace

double neighbour_noise(const std::vector<CoreSample>& cores, double radius_m) {
  if (cores.size() < 2) return 0.0;
  const NearestIndex index(positions(cores));
  std::vector<uint32_t> near;
  std::vector<double> differences;
  for (size_t i = 0; i < cores.size(); ++i) {
    index.within(cores[i].position_m.cast<float>(), radius_m, &near);
    double best = std::numeric_limits<double>::infinity();
    uint32_t nearest = uint32_t(i);
    for (uint32_t j : near) {
      const double dist = (cores[j].position_m - cores[i].position_m).squaredNorm();
      if (j != i && dist < best) best = dist, nearest = j;
    }
    if (nearest != i) differences.push_back(cores[i].distance_m - cores[nearest].distance_m);
  }
  if (differences.empty()) return 0.0;
  for (double& v : differences) v = std::abs(v);
  return 1.4826 * median_of(differences) / std::sqrt(2.0);
}

std::vector<char> stable_cores(const std::vector<CoreSample>& cores,
                               const std::vector<double>& residual_m, double band_m,
                               double radius_m) {
  if (cores.empty()) return {};
  const NearestIndex index(positions(cores));
  return stable_in(cores, index, residual_m, band_m, radius_m);
}

TileCorrection correct_tile(const std::vector<CoreSample>& cores, const Eigen::Vector3d& center_m,
                            double half_side_m, const TileCorrectionOptions& o) {
  TileCorrection out;
  out.cores = cores.size();
  if (cores.size() < o.min_stable_cores) {
    out.status = "too few cores";
    return out;
  }
  const NearestIndex index(positions(cores));
  out.noise_m = neighbour_noise(cores, o.leave_out_radius_m);
  const double band = std::max(o.significance_sigmas * out.noise_m, o.stable_floor_m);
  const Frame frame{center_m, half_side_m};

  std::optional<Candidate> best =
      refine(cores, index, frame, Vector6::Zero(), out.noise_m, band, o);
  const std::optional<Candidate> offset =
      refine(cores, index, frame, dominant_offset(cores, frame, o), out.noise_m, band, o);
  const double gain = o.min_support_gain * double(cores.size());
  if (offset && (!best || double(offset->stable) >= double(best->stable) + gain)) best = offset;
  if (!best) {
    out.status = "no constrained direction";
    return out;
  }
  out.stable = best->stable;
  out.fixed_directions = best->fixed;
  if (double(best->stable) < o.min_support_fraction * double(cores.size())) {
    out.status = "unsupported";
    return out;
  }
  const Eigen::Vector3d w = best->x.head<3>() / half_side_m, t = best->x.tail<3>();
  Pose3 T = Pose3::Identity();
  if (w.norm() > 0.0) T.linear() = Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix();
  T.translation() = center_m + t - T.linear() * center_m;  // p' = R (p - c) + c + t
  out.correction_m = t.norm();
  if (t.norm() > o.max_translation_m || w.norm() * 180.0 / M_PI > o.max_rotation_deg) {
    out.status = "too large";
    return out;
  }
  out.T_corrected_b = T;
  out.status = "corrected";
  return out;
}

double tile_registration_error(const std::vector<CoreSample>& cores, double confidence_z,
                               const TileCorrectionOptions& o, std::vector<char>* stable_out) {
  if (stable_out) stable_out->assign(cores.size(), 0);
  if (cores.size() < o.min_stable_cores) return -1.0;
  std::vector<double> residual(cores.size()), magnitude(cores.size());
  for (size_t i = 0; i < cores.size(); ++i)
    residual[i] = cores[i].distance_m, magnitude[i] = std::abs(cores[i].distance_m);
  const double spread = 1.4826 * median_of(magnitude);
  const double noise = neighbour_noise(cores, o.leave_out_radius_m);
  const double band =
      std::max(o.significance_sigmas * std::max(noise, spread), o.calibration_floor_m);
  const std::vector<char> stable = stable_cores(cores, residual, band, o.leave_out_radius_m);
  std::vector<double> excess;
  for (size_t i = 0; i < cores.size(); ++i)
    if (stable[i])
      excess.push_back(std::abs(cores[i].distance_m) / confidence_z - cores[i].statistical_m);
  if (stable_out) *stable_out = stable;
  if (excess.size() < o.min_stable_cores) return -1.0;
  const double level = std::erf(confidence_z / std::sqrt(2.0));  // 2 Phi(z) - 1
  const size_t k = std::min(excess.size() - 1, size_t(std::ceil(level * excess.size())) - 1);
  std::nth_element(excess.begin(), excess.begin() + k, excess.end());
  return std::max(0.0, excess[k]);
}

}  // namespace keel::compare
