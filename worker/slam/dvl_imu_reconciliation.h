// Temporal reconciliation of DVL and IMU measurements into pseudosensor measurements,
// Algorithm 1 and Eq. (17)-(19), seed 000.
#pragma once

#include <Eigen/Core>

#include <vector>

#include "worker/slam/sensor_samples.h"

namespace keel::slam {

struct ReconcileOptions {
  // Beyond the paper (its Sec. VII: "DVL signal drop-out"): two consecutive valid DVL samples
  // further apart than this are not bridged by interpolation, so no pseudo sample exists in
  // between and no DVL factor spans the dropout. 0.5 s is 10 periods of the 20 Hz DVL of
  // Table I and 2 periods of the slowest (4 Hz) rate of the DVL A50.
  double max_dvl_gap_s = 0.5;
};

// Algorithm 1, seed 000: for every IMU sample k with valid DVL samples l-1, l such that
// t_{l-1} <= t_k <= t_l, the DVL velocity linearly interpolated at t_k is paired with the gyro
// sample (Eq. (19)) and rotated into the IMU frame with R_imu_dvl (the rotation of T_B,B_o).
// IMU samples before the first or after the last valid DVL sample, or inside a gap longer than
// max_dvl_gap_s, produce nothing; an IMU sample stamped exactly like a DVL sample takes that
// sample's velocity. Samples flagged invalid are dropped first.
//
// The paper's listing advances D_{l-1} to the first DVL sample passed, which is only right when
// at most one DVL sample falls between two IMU samples; here the bracketing pair is always the
// nearest one, which is the same thing in that case and correct otherwise.
//
// Throws std::invalid_argument naming the stream and index on unsorted/duplicate stamps or
// non-finite values.
std::vector<PseudoSample> reconcile_dvl_imu(const std::vector<DvlSample>& dvl,
                                            const std::vector<ImuSample>& imu,
                                            const Eigen::Matrix3d& R_imu_dvl,
                                            const ReconcileOptions& options = {});

// Input checks shared with the solver: strictly increasing stamps, finite values.
void validate_imu_samples(const std::vector<ImuSample>& imu);
void validate_dvl_samples(const std::vector<DvlSample>& dvl);

}  // namespace keel::slam
