// Where hauv-hull lays its survey lanes and places foreign objects: a point of the hull's
// wetted starboard side by its position along the hull and around the section. Two hulls
// provide it: keel-sim's procedural hull (hull_model.h) and a user's CAD mesh (cad_hull.h).
#pragma once

#include "tests/sim/hull_model.h"

namespace keel::sim {

class HullSurface {
 public:
  virtual ~HullSurface() = default;
  // x_m: along the hull (CAD x) from the survey's centre, m. sigma: around the starboard
  // section, 0 at the keel and growing towards the waterline; the survey lanes lie at sigma
  // 0.33-0.85 (scenarios.cc), which on the procedural hull is its normalised arc length.
  virtual SurfacePoint surface(double x_m, double sigma) const = 0;
  // The survey's centre in the CAD frame, which the CAD-to-world misalignment turns about
  // (the procedural hull: its origin, at midship on the waterline).
  virtual Eigen::Vector3d survey_center() const = 0;
};

// The procedural hull: sigma is HullShape's normalised arc length (-1 port waterline, 0 keel,
// +1 starboard waterline); the survey is centred at midship.
class ProceduralHullSurface : public HullSurface {
 public:
  explicit ProceduralHullSurface(const HullOptions& options) : shape_(options) {}
  SurfacePoint surface(double x_m, double sigma) const override {
    return shape_.surface(2.0 * x_m / shape_.options().length_m, sigma);
  }
  Eigen::Vector3d survey_center() const override { return Eigen::Vector3d::Zero(); }

 private:
  HullShape shape_;
};

}  // namespace keel::sim
