#include "worker/compare/stable_registration.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <stdexcept>
#include <string>

#include "worker/compare/nearest_index.h"
#include "worker/compare/voxel_moments.h"
#include "core/robust_spread.h"
#include "core/parallel_for.h"

namespace keel::compare {
namespace {

void require(bool ok, const char* field, const char* expected) {
  if (!ok) throw std::invalid_argument(std::string(field) + ": expected " + expected);
}

struct Plane {
  Eigen::Vector3d centroid, normal;
};

// A's planes, one per voxel of side plane_radius / 2 whose neighbourhood is a surface.
std::vector<Plane> reference_planes(const std::vector<Eigen::Vector3f>& reference,
                                    const StableRegistrationOptions& o,
                                    std::vector<Eigen::Vector3f>* anchors) {
  const VoxelMoments voxels = voxelize(reference, 0.5 * o.plane_radius_m, false, o.threads);
  const NearestIndex index(voxels.means);
  std::vector<Plane> planes(voxels.voxels.size());
  std::vector<char> keep(voxels.voxels.size(), 0);
  keel::parallel_for(voxels.voxels.size(), o.threads, [&](size_t begin, size_t end) {
    std::vector<uint32_t> near;
    for (size_t v = begin; v < end; ++v) {
      index.within(voxels.means[v], o.plane_radius_m, &near);
      Moments sum;
      for (uint32_t u : near) sum.add(voxels.voxels[u]);
      const LocalPlane plane = fit_plane(sum);
      if (!plane.valid || plane.eigenvalues[0] > o.max_planar_ratio * plane.eigenvalues[1])
        continue;
      planes[v] = {plane.centroid, plane.normal};
      keep[v] = 1;
    }
  });
  std::vector<Plane> kept;
  for (size_t v = 0; v < planes.size(); ++v) {
    if (!keep[v]) continue;
    kept.push_back(planes[v]);
    anchors->push_back(voxels.means[v]);
  }
  return kept;
}

Pose3 exp_se3(const Eigen::Matrix<double, 6, 1>& xi) {
  Pose3 T = Pose3::Identity();
  const Eigen::Vector3d w = xi.head<3>();
  const double angle = w.norm();
  if (angle > 0.0) T.linear() = Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
  T.translation() = xi.tail<3>();
  return T;
}

}  // namespace

void validate(const StableRegistrationOptions& o) {
  require(std::isfinite(o.sample_spacing_m) && o.sample_spacing_m > 0, "sample_spacing_m", "> 0");
  require(std::isfinite(o.plane_radius_m) && o.plane_radius_m > 0, "plane_radius_m", "> 0");
  require(std::isfinite(o.max_correspondence_m) && o.max_correspondence_m > 0,
          "max_correspondence_m", "> 0");
  require(std::isfinite(o.stable_sigmas) && o.stable_sigmas > 0, "stable_sigmas", "> 0");
  require(std::isfinite(o.stable_floor_m) && o.stable_floor_m >= 0, "stable_floor_m", ">= 0");
  require(std::isfinite(o.max_planar_ratio) && o.max_planar_ratio > 0 && o.max_planar_ratio <= 1,
          "max_planar_ratio", "in (0, 1]");
  require(o.max_iterations >= 1 && o.max_iterations <= 1000, "max_iterations",
          "an integer in [1, 1000]");
}

StableRegistration register_stable(const std::vector<Eigen::Vector3f>& reference,
                                   const std::vector<Eigen::Vector3f>& moving,
                                   const Pose3& T_a_b_initial, const StableRegistrationOptions& o) {
  validate(o);
  if (reference.empty() || moving.empty())
    throw std::invalid_argument("registration: both clouds need points");
  std::vector<Eigen::Vector3f> anchors;
  const std::vector<Plane> planes = reference_planes(reference, o, &anchors);
  if (planes.size() < 6) throw std::runtime_error("registration: the reference has no surfaces");
  const NearestIndex plane_index(anchors);
  const VoxelMoments samples = voxelize(moving, o.sample_spacing_m, false, o.threads);

  StableRegistration out;
  out.samples = samples.voxels.size();
  out.T_a_b = T_a_b_initial;
  const size_t n = samples.voxels.size();
  std::vector<double> residual(n);
  std::vector<int> pair(n);
  std::vector<Eigen::Vector3d> moved(n);
  for (int iteration = 0; iteration < o.max_iterations; ++iteration) {
    if (o.check_canceled) o.check_canceled();
    // Pairs: each moved sample with A's nearest plane anchor.
    keel::parallel_for(n, o.threads, [&](size_t begin, size_t end) {
      for (size_t i = begin; i < end; ++i) {
        moved[i] = out.T_a_b * samples.voxels[i].mean;
        const Neighbour nb = plane_index.nearest(moved[i].cast<float>());
        pair[i] = nb.distance_m <= o.max_correspondence_m ? int(nb.index) : -1;
        if (pair[i] >= 0)
          residual[i] = planes[nb.index].normal.dot(moved[i] - planes[nb.index].centroid);
      }
    });
    std::vector<double> used;
    for (size_t i = 0; i < n; ++i)
      if (pair[i] >= 0) used.push_back(residual[i]);
    out.correspondences = used.size();
    // The stable band: residuals centred on 0 (a registered survey's stable pairs straddle
    // their planes), spread 1.4826 MAD about 0.
    for (double& r : used) r = std::abs(r);
    const double spread = 1.4826 * median_of(used);
    out.band_m = std::max(o.stable_sigmas * spread, o.stable_floor_m);

    Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> g = Eigen::Matrix<double, 6, 1>::Zero();
    double sum_squares = 0.0;
    size_t stable = 0;
    for (size_t i = 0; i < n; ++i) {
      if (pair[i] < 0 || std::abs(residual[i]) > out.band_m) continue;
      const Eigen::Vector3d& normal = planes[pair[i]].normal;
      // r(xi) = r + (q x n) . w + n . t for a left perturbation exp(xi) T.
      Eigen::Matrix<double, 6, 1> J;
      J.head<3>() = moved[i].cross(normal);
      J.tail<3>() = normal;
      H += J * J.transpose();
      g += J * residual[i];
      sum_squares += residual[i] * residual[i];
      ++stable;
    }
    out.stable = stable;
    out.rms_stable_m = stable ? std::sqrt(sum_squares / stable) : 0.0;
    if (stable < 6) throw std::runtime_error("registration: fewer than 6 stable pairs");
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eig(H);
    out.conditioning = eig.eigenvalues()[0] / std::max(eig.eigenvalues()[5], 1e-300);
    // Rotations about a far-away origin couple with translations; a tiny damping keeps a
    // degenerate direction (a corridor's axis) from running away instead of failing.
    const double damping = 1e-9 * H.trace();
    const Eigen::Matrix<double, 6, 1> xi =
        -(H + damping * Eigen::Matrix<double, 6, 6>::Identity()).ldlt().solve(g);
    out.T_a_b = exp_se3(xi) * out.T_a_b;
    out.iterations = iteration + 1;
    if (xi.tail<3>().norm() < o.converged_translation_m &&
        xi.head<3>().norm() < o.converged_rotation_rad) {
      out.converged = true;
      break;
    }
  }
  return out;
}

}  // namespace keel::compare
