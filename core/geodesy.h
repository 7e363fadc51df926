// WGS 84 geodetic coordinates <-> the world frame's local east-north-up frame at a stated
// origin (mission.yaml `origin:`), through PROJ: geodetic -> geocentric ECEF (EPSG:4979 ->
// EPSG:4978, `+proj=cart`) -> the topocentric rotation at the origin (`+proj=topocentric`,
// IOGP Guidance Note 7-2, method 9837). Heights are above the ellipsoid.
#pragma once

#include <Eigen/Core>

#include <memory>

namespace keel {

struct GeodeticPoint {
  double latitude_deg = 0.0;
  double longitude_deg = 0.0;
  double height_m = 0.0;
};

// Not thread-safe (a PROJ object is not): one frame per thread.
class LocalEnuFrame {
 public:
  // Fails (std::invalid_argument) on a latitude outside [-90, 90], a longitude outside
  // [-180, 360] or a non-finite value.
  explicit LocalEnuFrame(const GeodeticPoint& origin);
  ~LocalEnuFrame();
  LocalEnuFrame(LocalEnuFrame&&) noexcept;
  LocalEnuFrame& operator=(LocalEnuFrame&&) noexcept;

  const GeodeticPoint& origin() const { return origin_; }
  // East, north, up in metres of `point` relative to the origin.
  Eigen::Vector3d to_enu(const GeodeticPoint& point) const;
  GeodeticPoint to_geodetic(const Eigen::Vector3d& enu_m) const;

 private:
  struct Impl;
  GeodeticPoint origin_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace keel
