// A DVL's velocity from its beams' radial velocities: each beam i measures r_i = b_i . v + n_i
// (b_i the beam's unit direction in the DVL frame, v the DVL's velocity over the bottom in that
// frame, n_i ~ N(0, sigma_i^2)). The weighted least-squares solution
//   v = argmin sum_i ((b_i . v - r_i) / sigma_i)^2 = (B^T W B)^-1 B^T W r,  W = diag(sigma_i^-2)
// and its covariance (B^T W B)^-1 (Gauss-Markov; e.g. Kay, Fundamentals of Statistical Signal
// Processing I, Thm. 6.1) need three beams whose directions span 3-D: four beams over-determine
// v, three determine it exactly (a Janus DVL that lost one beam), fewer leave it unknown.
// Pure maths, no I/O.
#pragma once

#include <Eigen/Core>

#include <array>
#include <vector>

namespace keel::io {

struct BeamMeasurement {
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();  // unit, DVL frame, towards the bottom
  double velocity_m_s = 0.0;  // b . v: the DVL's velocity projected on the beam
  double sigma_m_s = 1.0;     // the beam's noise (std); > 0
  bool valid = true;          // the beam has bottom lock
};

struct BeamSolution {
  bool valid = false;  // false with fewer than 3 valid beams or directions that do not span 3-D
  int beams_used = 0;  // valid beams that entered the solution
  Eigen::Vector3d velocity_m_s = Eigen::Vector3d::Zero();      // DVL frame
  Eigen::Matrix3d covariance_m2_s2 = Eigen::Matrix3d::Zero();  // (B^T W B)^-1
};

// Beams with !valid, a non-finite velocity or a sigma that is not positive and finite are
// left out. The directions need not be unit (they are normalised).
BeamSolution solve_beam_velocity(const std::vector<BeamMeasurement>& beams);

// Janus geometry: beam k points `tilt_rad` off the DVL's +z axis (down), at azimuth
// azimuth_rad[k] from +x towards +y: b_k = (sin t cos a_k, sin t sin a_k, cos t).
std::vector<Eigen::Vector3d> janus_beam_directions(double tilt_rad,
                                                   const std::vector<double>& azimuth_rad);

// Water Linked DVL A50 (docs.waterlinked.com/dvl/axes: x forward, y right, z down; protocol
// transducer ids 0-3): four beams 22.5 degrees off the z axis (the A50 datasheet's beam
// angle), transducer id k at azimuth 135 + 90 k degrees from x towards y (0: 135, 1: 225,
// 2: 315, 3: 45). The assignment is the one that reproduces the A50's own velocities from its
// beam velocities in Water Linked's recordings (github.com/waterlinked/dvl-a50-ros-driver,
// data/01-06, commit e09ad0a: median difference 1.2 mm/s = the median figure of merit over 2357
// four-beam reports; the next best assignment differs by 18 mm/s); tests/worker/io/
// a50_dvl_test.cc checks it when KEEL_A50_BAGS holds them.
constexpr double kA50BeamTiltDeg = 22.5;
std::array<Eigen::Vector3d, 4> a50_beam_directions();

}  // namespace keel::io
