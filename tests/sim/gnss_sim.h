// GNSS fixes of a USV's antenna (issue 30): the true antenna position in the world frame (a
// local ENU frame at the mission's origin) plus Gaussian noise, no fix where a bridge deck hides
// the sky, and multipath near the piers: fixes biased by several metres whose status still says
// "fix", as receivers report them (the reflected signal looks like a direct one).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <vector>

#include "tests/sim/motion.h"

namespace keel::sim {

struct GnssOptions {
  double rate_hz = 2.0;
  double horizontal_sigma_m = 0.5;  // per axis (east, north)
  double vertical_sigma_m = 1.0;
  // Within `multipath_radius_m` (horizontal) of a reflector and outside every deck, a fix is
  // reflected with this probability: biased horizontally away from the reflector by a length
  // uniform in [bias_min, bias_max].
  double multipath_radius_m = 12.0;
  double multipath_probability = 0.5;
  double multipath_bias_min_m = 3.0, multipath_bias_max_m = 8.0;
};

// Where the sky is hidden (decks: axis-aligned footprints in world x-y) and what reflects (pier
// centres in world x-y). Empty for open water.
struct GnssEnvironment {
  std::vector<Eigen::AlignedBox2d> decks;
  std::vector<Eigen::Vector2d> reflectors;
};

enum class GnssFixKind { kClean = 0, kMultipath = 1, kNoFix = 2 };

struct GnssSimSample {
  int64_t t_ns = 0;  // since mission start
  GnssFixKind kind = GnssFixKind::kClean;
  Eigen::Vector3d antenna_true_world = Eigen::Vector3d::Zero();
  Eigen::Vector3d antenna_measured_world = Eigen::Vector3d::Zero();  // NaN without a fix
};

// Fixes at options.rate_hz over [0, duration_s]; noise from its own random stream (Stream::kGnss),
// so the other sensors' noise does not change when GNSS is simulated.
std::vector<GnssSimSample> simulate_gnss(const PathMotion& motion, double duration_s,
                                         const Eigen::Vector3d& t_body_antenna,
                                         const GnssEnvironment& environment,
                                         const GnssOptions& options, uint64_t seed);

}  // namespace keel::sim
