#include "tests/sim/gnss_sim.h"

#include <cmath>
#include <limits>

#include "tests/sim/inertial_sensors.h"
#include "tests/sim/rng.h"

namespace keel::sim {

std::vector<GnssSimSample> simulate_gnss(const PathMotion& motion, double duration_s,
                                         const Eigen::Vector3d& t_body_antenna,
                                         const GnssEnvironment& environment,
                                         const GnssOptions& options, uint64_t seed) {
  Rng rng(seed, Stream::kGnss);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<GnssSimSample> out;
  for (int64_t t_ns : sample_times_ns(options.rate_hz, duration_s)) {
    const KinematicState s = motion.state(t_ns * 1e-9);
    GnssSimSample g;
    g.t_ns = t_ns;
    g.antenna_true_world = s.p_world + s.q_world_body * t_body_antenna;
    const Eigen::Vector2d xy = g.antenna_true_world.head<2>();
    // Every draw is made whatever the fix's kind, so one fix's kind does not shift the noise
    // of the next ones.
    const Eigen::Vector3d noise(options.horizontal_sigma_m * rng.gaussian(),
                                options.horizontal_sigma_m * rng.gaussian(),
                                options.vertical_sigma_m * rng.gaussian());
    const double reflect_draw = rng.uniform();
    const double bias_m = rng.uniform(options.multipath_bias_min_m, options.multipath_bias_max_m);
    bool under_deck = false;
    for (const auto& deck : environment.decks) under_deck = under_deck || deck.contains(xy);
    const Eigen::Vector2d* nearest = nullptr;
    for (const auto& r : environment.reflectors)
      if (!nearest || (xy - r).norm() < (xy - *nearest).norm()) nearest = &r;
    g.antenna_measured_world = g.antenna_true_world + noise;
    if (under_deck) {
      g.kind = GnssFixKind::kNoFix;
      g.antenna_measured_world.setConstant(nan);
    } else if (nearest && (xy - *nearest).norm() < options.multipath_radius_m &&
               reflect_draw < options.multipath_probability) {
      g.kind = GnssFixKind::kMultipath;
      Eigen::Vector2d away = xy - *nearest;
      away = away.norm() > 1e-6 ? away.normalized() : Eigen::Vector2d::UnitX();
      g.antenna_measured_world.head<2>() += bias_m * away;
    }
    out.push_back(g);
  }
  return out;
}

}  // namespace keel::sim
