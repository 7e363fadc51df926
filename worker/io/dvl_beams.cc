#include "worker/io/dvl_beams.h"

#include <Eigen/Eigenvalues>

#include <cmath>

namespace keel::io {

BeamSolution solve_beam_velocity(const std::vector<BeamMeasurement>& beams) {
  BeamSolution out;
  // Normal equations N v = c with N = B^T W B, c = B^T W r.
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  for (const BeamMeasurement& beam : beams) {
    const double norm = beam.direction.norm();
    if (!beam.valid || !std::isfinite(beam.velocity_m_s) || !std::isfinite(beam.sigma_m_s) ||
        !(beam.sigma_m_s > 0.0) || !beam.direction.allFinite() || !(norm > 0.0))
      continue;
    const Eigen::Vector3d b = beam.direction / norm;
    const double weight = 1.0 / (beam.sigma_m_s * beam.sigma_m_s);
    normal += weight * b * b.transpose();
    rhs += weight * beam.velocity_m_s * b;
    ++out.beams_used;
  }
  if (out.beams_used < 3) return out;
  // Directions that (nearly) lie in a plane leave one velocity component unobserved; the
  // relative threshold is on N's eigenvalues, whatever the sigmas' scale.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(normal);
  const Eigen::Vector3d lambda = eigen.eigenvalues();  // ascending
  if (!(lambda(0) > 1e-9 * lambda(2))) return out;
  out.covariance_m2_s2 =
      eigen.eigenvectors() * lambda.cwiseInverse().asDiagonal() * eigen.eigenvectors().transpose();
  out.velocity_m_s = out.covariance_m2_s2 * rhs;
  out.valid = out.velocity_m_s.allFinite();
  return out;
}

std::vector<Eigen::Vector3d> janus_beam_directions(double tilt_rad,
                                                   const std::vector<double>& azimuth_rad) {
  std::vector<Eigen::Vector3d> out;
  out.reserve(azimuth_rad.size());
  for (double a : azimuth_rad)
    out.emplace_back(std::sin(tilt_rad) * std::cos(a), std::sin(tilt_rad) * std::sin(a),
                     std::cos(tilt_rad));
  return out;
}

std::array<Eigen::Vector3d, 4> a50_beam_directions() {
  const double deg = M_PI / 180.0;
  const auto b = janus_beam_directions(kA50BeamTiltDeg * deg,
                                       {135.0 * deg, 225.0 * deg, 315.0 * deg, 45.0 * deg});
  return {b[0], b[1], b[2], b[3]};
}

}  // namespace keel::io
