// Automatic refinement of a range sensor's extrinsic against a reference sensor (issue 31; the
// automatic counterpart of seed 000's manual Algorithm 3). The reference sensor's scans, placed
// in world with the body poses, make the reference map
//   p_world = T_world_body(t_j) * T_body_reference * p_reference;
// the candidate's scans are placed the same way through the unknown
//   p_world = T_world_body(t_i) * T_body_reference * T_reference_candidate * p_candidate,
// and T_reference_candidate minimises the robust point-to-plane cost of every candidate point
// against the local plane of its nearest reference point (plane_map.h), all scans jointly:
//   min_T  sum_i rho( n_i^T (p_world_i(T) - c_i) ),   rho = Huber or Cauchy,
// by Gauss-Newton with iteratively reweighted least squares, correspondences renewed between
// steps (ICP). The step is T <- T * (Exp(dphi), drho): translation and rotation perturbed on the
// right, in the candidate frame, order [x, y, z, roll, pitch, yaw].
//
// Observability (Zhang, Kaess, Singh, ICRA 2016): the information J^T W J is eigen-decomposed
// after scaling its rotation part by the candidate's RMS range L (a rotation dphi moves a
// point by ~L dphi, so both parts are in m^2 of point motion); directions whose eigenvalue is
// below `unobservable_ratio` times the largest are reported and the estimate is never moved
// along them (each step is solved in the observable subspace).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <string>
#include <vector>

#include "worker/mapping/plane_map.h"

namespace keel::mapping {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

// One scan: points in its sensor frame (deskewed), and the body pose at its stamp.
struct PlacedScan {
  Eigen::Isometry3d T_world_body = Eigen::Isometry3d::Identity();
  std::vector<Eigen::Vector3f> points;
};

enum class RobustLoss { kHuber, kCauchy };

struct ExtrinsicRefinementOptions {
  RobustLoss loss = RobustLoss::kHuber;
  double loss_scale_m = 0.05;  // residuals beyond it are down-weighted
  // Correspondence gate (distance to the nearest reference point): starts wide enough for a
  // few degrees of error at the scans' ranges and halves every outer iteration down to the
  // final gate.
  double max_correspondence_m = 1.0;
  double final_correspondence_m = 0.3;
  // A point farther than the gate from every reference point still matches a plane whose
  // nearest point is within this distance when the point lies within the gate of that plane
  // (0: never). For a sonar against a lidar: one sees under the water, the other above it,
  // and the piers' and walls' planes continue across the waterline.
  double plane_extrapolation_m = 0.0;
  int max_iterations = 30;     // outer (correspondence) iterations
  int gauss_newton_steps = 3;  // IRLS steps per set of correspondences
  double converged_translation_m = 1e-5;
  double converged_rotation_rad = 1e-6;
  double unobservable_ratio = 1e-2;  // of the largest eigenvalue of the scaled information
  // Overlap below which the candidate is refused: matched points at the initial extrinsic.
  size_t min_overlap_points = 200;
  double min_overlap_fraction = 0.02;
  // At most this many candidate points, evenly strided (0: all).
  size_t max_candidate_points = 300000;
  int histogram_bins = 20;
  PlaneMapOptions planes;
  int threads = 2;
};

// Point-to-plane distances (absolute, m) of the candidate points that found a planar match.
struct ResidualSummary {
  size_t points = 0;   // candidate points used
  size_t matched = 0;  // of them, with a planar reference neighbour within the final gate
  double median_m = 0.0, p90_m = 0.0, rms_m = 0.0;
  std::vector<double> histogram_edges_m;  // bins + 1, from 0 to the final gate
  std::vector<size_t> histogram_counts;
};

struct UnobservableDirection {
  Vector6d direction = Vector6d::Zero();  // unit, [x y z (m) roll pitch yaw (rad)], candidate frame
  double eigenvalue = 0.0;                // of the scaled information
  double ratio = 0.0;                     // eigenvalue / largest
};

struct ExtrinsicRefinementResult {
  bool refused = false;
  std::string reason;  // names both sensors when refused
  Eigen::Isometry3d T_reference_candidate = Eigen::Isometry3d::Identity();
  // sigma^2 (J^T W J)^-1, sigma^2 = sum w r^2 / (n - 6): the right perturbation's covariance;
  // huge (not infinite) along unobservable directions.
  Matrix6d covariance = Matrix6d::Zero();
  double residual_sigma_m = 0.0;
  double rotation_scale_m = 1.0;                         // L
  Vector6d information_eigenvalues = Vector6d::Zero();   // scaled information, ascending
  Matrix6d information_eigenvectors = Matrix6d::Zero();  // columns, unscaled and normalised
  std::vector<UnobservableDirection> unobservable;
  ResidualSummary before, after;
  int iterations = 0;
  bool converged = false;
  size_t reference_points = 0, reference_planar = 0;
};

// `reference_name` / `candidate_name` only for messages. Throws std::invalid_argument on
// empty reference scans or bad options; an overlap too small is a refusal, not an exception.
ExtrinsicRefinementResult refine_extrinsic(const std::vector<PlacedScan>& reference_scans,
                                           const std::vector<PlacedScan>& candidate_scans,
                                           const Eigen::Isometry3d& T_body_reference,
                                           const Eigen::Isometry3d& T_reference_candidate_initial,
                                           const std::string& reference_name,
                                           const std::string& candidate_name,
                                           const ExtrinsicRefinementOptions& options = {});

// The same against a reference map built once (PlaneMap over reference_map_points below), for
// several candidates of one reference; `options.planes` is then unused.
ExtrinsicRefinementResult refine_extrinsic(const PlaneMap& reference_map,
                                           const std::vector<PlacedScan>& candidate_scans,
                                           const Eigen::Isometry3d& T_body_reference,
                                           const Eigen::Isometry3d& T_reference_candidate_initial,
                                           const std::string& reference_name,
                                           const std::string& candidate_name,
                                           const ExtrinsicRefinementOptions& options = {});

// The reference scans placed in world: T_world_body * T_body_reference * p.
std::vector<Eigen::Vector3f> reference_map_points(const std::vector<PlacedScan>& reference_scans,
                                                  const Eigen::Isometry3d& T_body_reference);

// T * (Exp(delta_rotation), delta_translation): the perturbation the result's covariance and
// directions are expressed in.
Eigen::Isometry3d apply_right_perturbation(const Eigen::Isometry3d& T, const Vector6d& delta);

}  // namespace keel::mapping
