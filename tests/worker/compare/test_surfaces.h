// Noisy samples of analytic surfaces for the compare tests.
#pragma once

#include <Eigen/Geometry>

#include <cmath>
#include <random>
#include <vector>

namespace keel::compare::testing {

// Uniform samples of the rectangle origin + [0, a] u + [0, b] v, displaced along u x v by
// Gaussian noise of sigma_m.
inline void sample_rectangle(const Eigen::Vector3d& origin, const Eigen::Vector3d& u, double a,
                             const Eigen::Vector3d& v, double b, double density_per_m2,
                             double sigma_m, std::mt19937& rng, std::vector<Eigen::Vector3f>* out) {
  const Eigen::Vector3d n = u.cross(v).normalized();
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, sigma_m);
  const size_t count = size_t(std::llround(a * b * density_per_m2));
  for (size_t i = 0; i < count; ++i)
    out->push_back((origin + unit(rng) * a * u + unit(rng) * b * v + noise(rng) * n).cast<float>());
}

// Uniform samples of a sphere with radial Gaussian noise.
inline void sample_sphere(const Eigen::Vector3d& center, double radius_m, double density_per_m2,
                          double sigma_m, std::mt19937& rng, std::vector<Eigen::Vector3f>* out) {
  std::normal_distribution<double> gauss(0.0, 1.0), noise(0.0, sigma_m);
  const size_t count = size_t(std::llround(4.0 * M_PI * radius_m * radius_m * density_per_m2));
  for (size_t i = 0; i < count; ++i) {
    Eigen::Vector3d d(gauss(rng), gauss(rng), gauss(rng));
    d.normalize();
    out->push_back((center + (radius_m + noise(rng)) * d).cast<float>());
  }
}

// The faces of an axis-aligned box (all six), sampled.
inline void sample_box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double density,
                       double sigma_m, std::mt19937& rng, std::vector<Eigen::Vector3f>* out) {
  const Eigen::Vector3d e = hi - lo;
  const Eigen::Vector3d X = Eigen::Vector3d::UnitX(), Y = Eigen::Vector3d::UnitY(),
                        Z = Eigen::Vector3d::UnitZ();
  sample_rectangle(lo, X, e.x(), Y, e.y(), density, sigma_m, rng, out);
  sample_rectangle(lo + e.z() * Z, X, e.x(), Y, e.y(), density, sigma_m, rng, out);
  sample_rectangle(lo, X, e.x(), Z, e.z(), density, sigma_m, rng, out);
  sample_rectangle(lo + e.y() * Y, X, e.x(), Z, e.z(), density, sigma_m, rng, out);
  sample_rectangle(lo, Y, e.y(), Z, e.z(), density, sigma_m, rng, out);
  sample_rectangle(lo + e.x() * X, Y, e.y(), Z, e.z(), density, sigma_m, rng, out);
}

}  // namespace keel::compare::testing
