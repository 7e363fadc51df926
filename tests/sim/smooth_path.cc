#include "tests/sim/smooth_path.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace keel::sim {

CubicSpline1d::CubicSpline1d(std::vector<double> knots, std::vector<double> values)
    : knots_(std::move(knots)), values_(std::move(values)) {
  const size_t n = knots_.size();
  if (n < 2 || values_.size() != n) throw std::invalid_argument("CubicSpline1d: need >= 2 knots");
  second_.assign(n, 0.0);
  if (n == 2) return;
  // Tridiagonal system for the natural spline (M_0 = M_{n-1} = 0), Thomas algorithm.
  std::vector<double> diag(n, 1.0), upper(n, 0.0), rhs(n, 0.0);
  for (size_t i = 1; i + 1 < n; ++i) {
    const double h0 = knots_[i] - knots_[i - 1], h1 = knots_[i + 1] - knots_[i];
    const double lower = h0 / 6.0;
    diag[i] = (h0 + h1) / 3.0;
    upper[i] = h1 / 6.0;
    rhs[i] = (values_[i + 1] - values_[i]) / h1 - (values_[i] - values_[i - 1]) / h0;
    const double m = lower / diag[i - 1];
    diag[i] -= m * upper[i - 1];
    rhs[i] -= m * rhs[i - 1];
  }
  for (size_t i = n - 2; i >= 1; --i) second_[i] = (rhs[i] - upper[i] * second_[i + 1]) / diag[i];
}

void CubicSpline1d::evaluate(double u, double* y, double* dy, double* ddy) const {
  u = std::clamp(u, knots_.front(), knots_.back());
  size_t i = std::upper_bound(knots_.begin(), knots_.end(), u) - knots_.begin();
  i = std::clamp<size_t>(i, 1, knots_.size() - 1) - 1;
  const double h = knots_[i + 1] - knots_[i];
  const double a = (knots_[i + 1] - u) / h, b = (u - knots_[i]) / h;
  const double m0 = second_[i], m1 = second_[i + 1];
  *y = a * values_[i] + b * values_[i + 1] +
       ((a * a * a - a) * m0 + (b * b * b - b) * m1) * h * h / 6.0;
  *dy = (values_[i + 1] - values_[i]) / h +
        ((1.0 - 3.0 * a * a) * m0 + (3.0 * b * b - 1.0) * m1) * h / 6.0;
  *ddy = a * m0 + b * m1;
}

namespace {
constexpr int kTablePerSegment = 32;
// 5-point Gauss-Legendre nodes and weights on [-1, 1].
constexpr double kGaussNode[5] = {0.0, -0.5384693101056831, 0.5384693101056831, -0.9061798459386640,
                                  0.9061798459386640};
constexpr double kGaussWeight[5] = {0.5688888888888889, 0.4786286704993665, 0.4786286704993665,
                                    0.2369268850561891, 0.2369268850561891};
}  // namespace

SmoothPath::SmoothPath(const std::vector<Eigen::Vector3d>& waypoints,
                       const std::vector<std::vector<double>>& extra) {
  if (waypoints.size() < 2) throw std::invalid_argument("SmoothPath: need >= 2 waypoints");
  std::vector<double> knots{0.0}, xs, ys, zs;
  for (size_t i = 1; i < waypoints.size(); ++i) {
    const double chord = (waypoints[i] - waypoints[i - 1]).norm();
    if (chord < 1e-9) throw std::invalid_argument("SmoothPath: repeated waypoint");
    knots.push_back(knots.back() + chord);
  }
  for (const auto& w : waypoints) {
    xs.push_back(w.x());
    ys.push_back(w.y());
    zs.push_back(w.z());
  }
  x_ = CubicSpline1d(knots, xs);
  y_ = CubicSpline1d(knots, ys);
  z_ = CubicSpline1d(knots, zs);
  for (const auto& channel : extra) extra_.emplace_back(knots, channel);
  u_end_ = knots.back();
  // Arc-length table: fine steps in u, each integrated with Gauss-Legendre.
  table_u_.push_back(0.0);
  cumulative_.push_back(0.0);
  for (size_t seg = 0; seg + 1 < knots.size(); ++seg) {
    for (int k = 1; k <= kTablePerSegment; ++k) {
      const double u0 = table_u_.back();
      const double u1 = knots[seg] + (knots[seg + 1] - knots[seg]) * k / kTablePerSegment;
      cumulative_.push_back(cumulative_.back() + integrate(u0, u1));
      table_u_.push_back(u1);
    }
  }
}

double SmoothPath::waypoint_arc_length(size_t i) const {
  // The table holds kTablePerSegment steps per segment, so waypoint i is entry i * that.
  return cumulative_.at(i * kTablePerSegment);
}

double SmoothPath::speed_u(double u) const {
  double v, dx, dy, dz, dd;
  x_.evaluate(u, &v, &dx, &dd);
  y_.evaluate(u, &v, &dy, &dd);
  z_.evaluate(u, &v, &dz, &dd);
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

double SmoothPath::integrate(double u0, double u1) const {
  const double half = 0.5 * (u1 - u0), mid = 0.5 * (u1 + u0);
  double sum = 0.0;
  for (int i = 0; i < 5; ++i) sum += kGaussWeight[i] * speed_u(mid + half * kGaussNode[i]);
  return sum * half;
}

double SmoothPath::parameter_at(double s) const {
  s = std::clamp(s, 0.0, length());
  size_t i = std::upper_bound(cumulative_.begin(), cumulative_.end(), s) - cumulative_.begin();
  i = std::clamp<size_t>(i, 1, cumulative_.size() - 1) - 1;
  const double u0 = table_u_[i], u1 = table_u_[i + 1];
  const double s0 = cumulative_[i], s1 = cumulative_[i + 1];
  double u = s1 > s0 ? u0 + (u1 - u0) * (s - s0) / (s1 - s0) : u0;
  // Newton on S(u) = s; the table step is small, so a few iterations reach 1e-12.
  for (int iter = 0; iter < 6; ++iter) {
    const double f = s0 + integrate(u0, u) - s;
    const double step = f / std::max(speed_u(u), 1e-12);
    u = std::clamp(u - step, u0, u1);
    if (std::abs(step) < 1e-13) break;
  }
  return u;
}

SmoothPath::Point SmoothPath::at(double s) const {
  const double u = parameter_at(s);
  Eigen::Vector3d p, du, ddu;
  x_.evaluate(u, &p.x(), &du.x(), &ddu.x());
  y_.evaluate(u, &p.y(), &du.y(), &ddu.y());
  z_.evaluate(u, &p.z(), &du.z(), &ddu.z());
  const double speed = std::max(du.norm(), 1e-12);
  Point out;
  out.p = p;
  out.tangent = du / speed;
  // d2p/ds2 = (p_uu - (p_uu . T) T) / |p_u|^2.
  out.d2p_ds2 = (ddu - ddu.dot(out.tangent) * out.tangent) / (speed * speed);
  return out;
}

void SmoothPath::extra_at(size_t channel, double s, double* value, double* d_ds,
                          double* d2_ds2) const {
  const double u = parameter_at(s);
  double du_value, ddu_value;
  extra_.at(channel).evaluate(u, value, &du_value, &ddu_value);
  Eigen::Vector3d p, du, ddu;
  x_.evaluate(u, &p.x(), &du.x(), &ddu.x());
  y_.evaluate(u, &p.y(), &du.y(), &ddu.y());
  z_.evaluate(u, &p.z(), &du.z(), &ddu.z());
  const double speed = std::max(du.norm(), 1e-12);
  // u'(s) = 1/|p_u|, u''(s) = -(p_u . p_uu) / |p_u|^4.
  const double u_s = 1.0 / speed;
  const double u_ss = -du.dot(ddu) / (speed * speed * speed * speed);
  *d_ds = du_value * u_s;
  *d2_ds2 = ddu_value * u_s * u_s + du_value * u_ss;
}

}  // namespace keel::sim
