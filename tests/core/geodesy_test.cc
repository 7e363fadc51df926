// LocalEnuFrame against closed forms: the geodetic -> ECEF formula and the ENU rotation
// (IOGP Guidance Note 7-2, 2.2.1 and 4.1.1), and the ellipsoid's radii of curvature.
#include "core/geodesy.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace keel {
namespace {

constexpr double kA = 6378137.0;            // WGS 84 semi-major axis, m
constexpr double kF = 1.0 / 298.257223563;  // WGS 84 flattening
constexpr double kE2 = kF * (2.0 - kF);     // first eccentricity squared
constexpr double kDeg = M_PI / 180.0;

// Prime vertical radius N(phi) and meridian radius M(phi).
double prime_vertical_radius(double phi) {
  return kA / std::sqrt(1 - kE2 * std::sin(phi) * std::sin(phi));
}
double meridian_radius(double phi) {
  return kA * (1 - kE2) / std::pow(1 - kE2 * std::sin(phi) * std::sin(phi), 1.5);
}

Eigen::Vector3d ecef(const GeodeticPoint& p) {
  const double phi = p.latitude_deg * kDeg, lam = p.longitude_deg * kDeg;
  const double n = prime_vertical_radius(phi);
  return {(n + p.height_m) * std::cos(phi) * std::cos(lam),
          (n + p.height_m) * std::cos(phi) * std::sin(lam),
          (n * (1 - kE2) + p.height_m) * std::sin(phi)};
}

Eigen::Vector3d enu_oracle(const GeodeticPoint& origin, const GeodeticPoint& p) {
  const double phi = origin.latitude_deg * kDeg, lam = origin.longitude_deg * kDeg;
  Eigen::Matrix3d R;                      // rows: east, north, up in ECEF
  R << -std::sin(lam), std::cos(lam), 0,  //
      -std::sin(phi) * std::cos(lam), -std::sin(phi) * std::sin(lam), std::cos(phi),  //
      std::cos(phi) * std::cos(lam), std::cos(phi) * std::sin(lam), std::sin(phi);
  return R * (ecef(p) - ecef(origin));
}

const GeodeticPoint kHamburg{53.5461, 9.9661, 42.0};

TEST(Geodesy, OriginIsZeroAndRoundTripsWithinAMillimetre) {
  for (const GeodeticPoint& o :
       {kHamburg, GeodeticPoint{-33.86, 151.21, -20.0}, GeodeticPoint{0.0, -179.5, 0.0},
        GeodeticPoint{78.2, 15.6, 300.0}}) {
    LocalEnuFrame frame(o);
    EXPECT_LT(frame.to_enu(o).norm(), 1e-6);
    const GeodeticPoint back = frame.to_geodetic(Eigen::Vector3d::Zero());
    // 1 mm in degrees of latitude is ~9e-9; in longitude scaled by cos(latitude).
    const double phi = o.latitude_deg * kDeg;
    EXPECT_LT(std::abs(back.latitude_deg - o.latitude_deg) * kDeg * meridian_radius(phi), 1e-3);
    EXPECT_LT(std::abs(back.longitude_deg - o.longitude_deg) * kDeg * prime_vertical_radius(phi) *
                  std::cos(phi),
              1e-3);
    EXPECT_LT(std::abs(back.height_m - o.height_m), 1e-3);
  }
}

TEST(Geodesy, MatchesTheEcefAndRotationClosedForm) {
  LocalEnuFrame frame(kHamburg);
  for (const GeodeticPoint& p :
       {GeodeticPoint{53.55, 9.97, 40.0}, GeodeticPoint{53.5, 9.9, 0.0},
        GeodeticPoint{53.6, 10.1, 1000.0}, GeodeticPoint{53.5461, 9.9661, -5.0}}) {
    const Eigen::Vector3d enu = frame.to_enu(p);
    EXPECT_LT((enu - enu_oracle(kHamburg, p)).norm(), 1e-3) << enu.transpose();
    const GeodeticPoint back = frame.to_geodetic(enu);
    EXPECT_LT((frame.to_enu(back) - enu).norm(), 1e-3);
    EXPECT_NEAR(back.height_m, p.height_m, 1e-3);
  }
}

// 1 km east / north in the tangent plane against the radii of curvature: dlambda * (N + h)
// cos(phi) and dphi * (M + h) are arc lengths; the tangent-plane distance differs from them by
// less than 1 mm over 1 km (chord/arc d^3 / (6 R^2) ~ 1e-5 m, M's change over 1 km ~ 1e-3 m),
// so the tolerance is 1 cm.
TEST(Geodesy, OneKilometreEastAndNorthAgreeWithTheRadiiOfCurvature) {
  LocalEnuFrame frame(kHamburg);
  const double phi = kHamburg.latitude_deg * kDeg, h = kHamburg.height_m;
  const GeodeticPoint east = frame.to_geodetic({1000.0, 0.0, 0.0});
  const double east_arc_m = (east.longitude_deg - kHamburg.longitude_deg) * kDeg *
                            (prime_vertical_radius(phi) + h) * std::cos(phi);
  EXPECT_NEAR(east_arc_m, 1000.0, 0.01);
  const GeodeticPoint north = frame.to_geodetic({0.0, 1000.0, 0.0});
  const double north_arc_m =
      (north.latitude_deg - kHamburg.latitude_deg) * kDeg * (meridian_radius(phi) + h);
  EXPECT_NEAR(north_arc_m, 1000.0, 0.01);
  EXPECT_NEAR(north.longitude_deg, kHamburg.longitude_deg, 1e-12);
  // The tangent plane leaves the ellipsoid: 1 km away it is d^2 / (2 R) above it.
  EXPECT_NEAR(north.height_m - h, 1e6 / (2 * (meridian_radius(phi) + h)), 0.01);
  const GeodeticPoint up = frame.to_geodetic({0.0, 0.0, 1000.0});
  EXPECT_NEAR(up.height_m, h + 1000.0, 1e-3);
}

TEST(Geodesy, RefusesAnOriginOffTheEarth) {
  EXPECT_THROW(LocalEnuFrame({91.0, 0.0, 0.0}), std::invalid_argument);
  EXPECT_THROW(LocalEnuFrame({0.0, 400.0, 0.0}), std::invalid_argument);
  EXPECT_THROW(LocalEnuFrame({NAN, 0.0, 0.0}), std::invalid_argument);
}

}  // namespace
}  // namespace keel
