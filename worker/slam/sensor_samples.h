// In-memory sensor samples the refine solver consumes (no I/O here: readers convert to these).
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <vector>

#include "core/time.h"

namespace keel::slam {

// One IMU sample in the IMU frame B, Eq. (9) and (5), seed 000.
struct ImuSample {
  TimeNs t_ns = 0;
  Eigen::Vector3d gyro_radps = Eigen::Vector3d::Zero();  // body rate
  Eigen::Vector3d accel_mps2 = Eigen::Vector3d::Zero();  // specific force (+g on z at rest)
};

// One DVL sample: velocity of the DVL relative to the bottom, in the DVL frame B_o, Eq. (10).
struct DvlSample {
  TimeNs t_ns = 0;
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();
  bool valid = true;  // false marks a dropout (no bottom lock)
};

// A pseudosensor measurement P_k of Eq. (19): the IMU gyro sample at t_k and the DVL
// velocity linearly interpolated at t_k (Algorithm 1), in both the DVL frame and rotated into
// the IMU frame B with the DVL-IMU extrinsic rotation.
struct PseudoSample {
  TimeNs t_ns = 0;
  Eigen::Vector3d gyro_radps = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_dvl_mps = Eigen::Vector3d::Zero();  // in B_o
  Eigen::Vector3d velocity_imu_mps = Eigen::Vector3d::Zero();  // R_imu_dvl * velocity_dvl_mps
  double dvl_period_s = 0.0;  // spacing of the two DVL samples it was interpolated from
};

// Calls fn(sample, dt_s) for the zero-order-hold pieces of `samples` that tile [t_a, t_b]:
// sample k holds over [t_k, t_{k+1}), clipped to the interval. Returns false, calling nothing,
// when the samples do not cover [t_a, t_b] or two consecutive samples inside it are more than
// max_gap_ns apart. `samples` must be sorted by t_ns.
template <class Sample, class Fn>
bool for_each_hold_segment(const std::vector<Sample>& samples, TimeNs t_a, TimeNs t_b,
                           TimeNs max_gap_ns, Fn&& fn) {
  if (samples.empty() || t_b <= t_a) return false;
  if (samples.front().t_ns > t_a || samples.back().t_ns < t_b) return false;
  size_t lo = 0, hi = samples.size();  // last index with t_ns <= t_a
  while (hi - lo > 1) {
    const size_t mid = (lo + hi) / 2;
    (samples[mid].t_ns <= t_a ? lo : hi) = mid;
  }
  size_t k_end = lo;
  for (size_t k = lo; samples[k].t_ns < t_b; ++k) {
    if (samples[k + 1].t_ns - samples[k].t_ns > max_gap_ns) return false;
    k_end = k;
  }
  for (size_t k = lo; k <= k_end; ++k) {
    const TimeNs start = std::max(samples[k].t_ns, t_a);
    const TimeNs end = std::min(samples[k + 1].t_ns, t_b);
    if (end > start) fn(samples[k], ns_to_seconds(end - start));
  }
  return true;
}

}  // namespace keel::slam
