#include "worker/slam/dvl_imu_reconciliation.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace keel::slam {
namespace {

template <class Sample>
void check_stamps(const std::vector<Sample>& samples, const char* stream) {
  for (size_t k = 1; k < samples.size(); ++k) {
    if (samples[k].t_ns <= samples[k - 1].t_ns) {
      throw std::invalid_argument(
          std::string(stream) + " sample " + std::to_string(k) + ": timestamp " +
          std::to_string(samples[k].t_ns) + " ns is not after the previous one (" +
          std::to_string(samples[k - 1].t_ns) + " ns); expected strictly increasing stamps");
    }
  }
}

[[noreturn]] void throw_non_finite(const char* stream, size_t k, const char* field) {
  throw std::invalid_argument(std::string(stream) + " sample " + std::to_string(k) + ": " + field +
                              " is not finite");
}

// Spacing (s) from valid[l] to the nearer neighbour that is not a dropout gap; the gap
// threshold when both are gaps (an isolated sample).
double neighbour_spacing_s(const std::vector<const DvlSample*>& valid, size_t l,
                           TimeNs max_gap_ns) {
  TimeNs best = max_gap_ns;
  if (l > 0) best = std::min(best, valid[l]->t_ns - valid[l - 1]->t_ns);
  if (l + 1 < valid.size()) best = std::min(best, valid[l + 1]->t_ns - valid[l]->t_ns);
  return ns_to_seconds(best);
}

}  // namespace

void validate_imu_samples(const std::vector<ImuSample>& imu) {
  check_stamps(imu, "imu");
  for (size_t k = 0; k < imu.size(); ++k) {
    if (!imu[k].gyro_radps.allFinite()) throw_non_finite("imu", k, "gyro_radps");
    if (!imu[k].accel_mps2.allFinite()) throw_non_finite("imu", k, "accel_mps2");
  }
}

void validate_dvl_samples(const std::vector<DvlSample>& dvl) {
  check_stamps(dvl, "dvl");
  for (size_t k = 0; k < dvl.size(); ++k) {
    if (dvl[k].valid && !dvl[k].velocity_mps.allFinite()) {
      throw_non_finite("dvl", k, "velocity_mps (of a sample marked valid)");
    }
  }
}

std::vector<PseudoSample> reconcile_dvl_imu(const std::vector<DvlSample>& dvl,
                                            const std::vector<ImuSample>& imu,
                                            const Eigen::Matrix3d& R_imu_dvl,
                                            const ReconcileOptions& options) {
  validate_imu_samples(imu);
  validate_dvl_samples(dvl);
  std::vector<const DvlSample*> valid;  // Q_D of Eq. (17), dropouts removed
  valid.reserve(dvl.size());
  for (const DvlSample& d : dvl) {
    if (d.valid) valid.push_back(&d);
  }
  std::vector<PseudoSample> out;  // Q_P of Eq. (19)
  if (valid.size() < 2) return out;
  const TimeNs max_gap_ns = seconds_to_ns(options.max_dvl_gap_s);
  out.reserve(imu.size());
  size_t l = 0;  // D_l: the first valid DVL sample with t_l >= t_k
  for (const ImuSample& s : imu) {
    if (s.t_ns < valid.front()->t_ns) continue;  // Algorithm 1, lines 4-8
    while (l < valid.size() && valid[l]->t_ns < s.t_ns) ++l;
    if (l == valid.size()) break;  // Q_D exhausted: the loop of line 10 ends
    PseudoSample p;
    p.t_ns = s.t_ns;
    p.gyro_radps = s.gyro_radps;
    if (valid[l]->t_ns == s.t_ns) {
      // A DVL sample at the IMU time is used as it is, even next to a dropout; its noise
      // density uses the spacing to a neighbour that is not a gap.
      p.velocity_dvl_mps = valid[l]->velocity_mps;
      p.dvl_period_s = neighbour_spacing_s(valid, l, max_gap_ns);
    } else {
      const DvlSample& d0 = *valid[l - 1];
      const DvlSample& d1 = *valid[l];
      const TimeNs span_ns = d1.t_ns - d0.t_ns;
      if (span_ns > max_gap_ns) continue;  // a dropout: not bridged
      // Line 22: LinearlyInterpolate(t_k, D_l, D_{l-1}).
      const double alpha = static_cast<double>(s.t_ns - d0.t_ns) / static_cast<double>(span_ns);
      p.velocity_dvl_mps = (1.0 - alpha) * d0.velocity_mps + alpha * d1.velocity_mps;
      p.dvl_period_s = ns_to_seconds(span_ns);
    }
    p.velocity_imu_mps = R_imu_dvl * p.velocity_dvl_mps;  // B~v = R_B,Bo * Bo~v
    out.push_back(p);
  }
  return out;
}

}  // namespace keel::slam
