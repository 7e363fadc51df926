// A C2 path through waypoints (natural cubic spline, chord-length knots) with exact
// arc-length access, so a vehicle can follow it at a prescribed speed and its velocity and
// acceleration are analytic (the IMU and DVL simulators need exact derivatives).
#pragma once

#include <Eigen/Core>

#include <vector>

namespace keel::sim {

// Natural cubic spline y(u) through (knots[i], values[i]).
class CubicSpline1d {
 public:
  CubicSpline1d() = default;
  CubicSpline1d(std::vector<double> knots, std::vector<double> values);
  // Value, first and second derivative at u (clamped to the knot range).
  void evaluate(double u, double* y, double* dy, double* ddy) const;

 private:
  std::vector<double> knots_, values_, second_;  // second_: y'' at the knots
};

class SmoothPath {
 public:
  // waypoints: at least 2 distinct points. extra: optional scalar channels (e.g. a servo
  // angle) given per waypoint and interpolated with the same parameter.
  explicit SmoothPath(const std::vector<Eigen::Vector3d>& waypoints,
                      const std::vector<std::vector<double>>& extra = {});

  double length() const { return cumulative_.back(); }
  // Arc length at waypoint i (e.g. where a lap starts on a path of repeated laps).
  double waypoint_arc_length(size_t i) const;

  struct Point {
    Eigen::Vector3d p;        // position
    Eigen::Vector3d tangent;  // dp/ds (unit)
    Eigen::Vector3d d2p_ds2;  // curvature vector
  };
  // The point at arc length s in [0, length()] (clamped).
  Point at(double s) const;
  // Extra channel c at arc length s: value and its derivatives with respect to s.
  void extra_at(size_t channel, double s, double* value, double* d_ds, double* d2_ds2) const;

 private:
  double parameter_at(double s) const;  // u(s)
  double speed_u(double u) const;       // |dp/du|
  double integrate(double u0, double u1) const;

  CubicSpline1d x_, y_, z_;
  std::vector<CubicSpline1d> extra_;
  double u_end_ = 0.0;
  std::vector<double> table_u_, cumulative_;  // arc length at table_u_
};

}  // namespace keel::sim
