// The plain value of a double or of a ceres::Jet, for the mesh queries inside auto-diffed
// factors: the query picks the triangle at the current value, and the factor then
// differentiates the closed form on that triangle.
#pragma once

#include <ceres/jet.h>

#include <Eigen/Core>

#include <type_traits>

namespace keel::ba {

inline double jet_value(double x) { return x; }
template <typename T, int N>
double jet_value(const ceres::Jet<T, N>& x) {
  return x.a;
}

template <typename T>
Eigen::Vector3d jet_value(const Eigen::Matrix<T, 3, 1>& v) {
  return Eigen::Vector3d(jet_value(v[0]), jet_value(v[1]), jet_value(v[2]));
}

}  // namespace keel::ba
