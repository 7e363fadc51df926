#include "worker/slam/refine_solver.h"

#include <ceres/ceres.h>
#include <ceres/normal_prior.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

#include "core/suitesparse_memory.h"
#include "worker/slam/dvl_factor.h"
#include "worker/slam/imu_factor.h"
#include "worker/slam/information.h"
#include "worker/slam/manifolds.h"
#include "worker/slam/prior_factors.h"
#include "worker/slam/refine_edges.h"
#include "worker/slam/relative_pose_factor.h"
#include "worker/slam/so3.h"

namespace keel::slam {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// The estimated states, in the IMU frame B (Eq. (2) plus b^v, s_d and R_B,Bo): the Ceres
// parameter blocks, all in one buffer. Per keyframe the pose T_world_imu (7, manifolds.h
// layout), the velocity, the gyro, accelerometer and DVL biases and the MAP drift
// (MapAnchorFactor, world frame), 3 each; then s_d (1) and R_B,Bo (4). Ceres's Covariance
// orders the blocks by their address, and separate allocations land in an order that follows
// the heap's history: the sigmas of s_d and R_B,Bo changed in their last digits with an
// option of another stage or the number of cores. One buffer fixes that order.
class States {
 public:
  explicit States(size_t keyframes)
      : keyframes_(keyframes), values_(keyframes * kKeyframeStride + 5, 0.0) {
    q_imu_dvl()[3] = 1.0;
  }

  size_t keyframes() const { return keyframes_; }
  double* pose(size_t k) { return at(k, 0); }
  const double* pose(size_t k) const { return at(k, 0); }
  double* vel(size_t k) { return at(k, 7); }
  const double* vel(size_t k) const { return at(k, 7); }
  double* bg(size_t k) { return at(k, 10); }
  const double* bg(size_t k) const { return at(k, 10); }
  double* ba(size_t k) { return at(k, 13); }
  const double* ba(size_t k) const { return at(k, 13); }
  double* bv(size_t k) { return at(k, 16); }
  const double* bv(size_t k) const { return at(k, 16); }
  double* drift(size_t k) { return at(k, 19); }
  const double* drift(size_t k) const { return at(k, 19); }
  double* scale() { return &values_[keyframes_ * kKeyframeStride]; }
  const double* scale() const { return &values_[keyframes_ * kKeyframeStride]; }
  double* q_imu_dvl() { return scale() + 1; }
  const double* q_imu_dvl() const { return scale() + 1; }

 private:
  static constexpr size_t kKeyframeStride = 22;
  double* at(size_t k, size_t offset) { return &values_[k * kKeyframeStride + offset]; }
  const double* at(size_t k, size_t offset) const { return &values_[k * kKeyframeStride + offset]; }

  size_t keyframes_;
  std::vector<double> values_;  // sized once: Ceres keeps pointers into it
};

void set_vec3(const Eigen::Vector3d& v, double* block) { std::copy(v.data(), v.data() + 3, block); }

struct Interval {
  std::shared_ptr<const ImuPreintegration> imu;  // null: no I_ij
  std::shared_ptr<const DvlPreintegration> dvl;  // null: no D_ij
};

// ---- Steps 1-2: inputs and edges: refine_edges.cc --------------------------------------------

// ---- Step 4: initial states -----------------------------------------------------------------

const PseudoSample* nearest_pseudo(const std::vector<PseudoSample>& pseudo, TimeNs t_ns,
                                   TimeNs max_diff_ns) {
  auto it = std::lower_bound(pseudo.begin(), pseudo.end(), t_ns,
                             [](const PseudoSample& p, TimeNs t) { return p.t_ns < t; });
  const PseudoSample* best = nullptr;
  if (it != pseudo.end()) best = &*it;
  if (it != pseudo.begin() && (best == nullptr || t_ns - (it - 1)->t_ns < best->t_ns - t_ns)) {
    best = &*(it - 1);
  }
  if (best == nullptr || std::abs(best->t_ns - t_ns) > max_diff_ns) return nullptr;
  return best;
}

States initial_states(const std::vector<Pose3>& T_world_imu, const std::vector<TimeNs>& t_ns,
                      const std::vector<PseudoSample>& pseudo, const Pose3& T_imu_dvl,
                      const RefineOptions& opt) {
  const size_t n = T_world_imu.size();
  States s(n);
  *s.scale() = opt.dvl_scale_initial;
  set_rotation_block(T_imu_dvl.linear(), s.q_imu_dvl());
  for (size_t k = 0; k < n; ++k) {
    set_pose_block(T_world_imu[k], s.pose(k));
    // Velocity: the DVL's (Eq. (8) inverted, lever arm neglected) where there is one, else the
    // central difference of the initial keyframe positions.
    Eigen::Vector3d v;
    const PseudoSample* p = nearest_pseudo(pseudo, t_ns[k], seconds_to_ns(0.1));
    if (p != nullptr) {
      v = T_world_imu[k].linear() * T_imu_dvl.linear() * p->velocity_dvl_mps / *s.scale();
    } else {
      const size_t a = k == 0 ? 0 : k - 1, b = k + 1 == n ? k : k + 1;
      v = (T_world_imu[b].translation() - T_world_imu[a].translation()) /
          ns_to_seconds(t_ns[b] - t_ns[a]);
    }
    set_vec3(v, s.vel(k));
  }
  return s;
}

Eigen::Vector3d vec(const double* b) { return Eigen::Vector3d(b[0], b[1], b[2]); }

// ---- Step 5: preintegration and graph -------------------------------------------------------

std::vector<Interval> preintegrate(const RefineInput& in, const std::vector<PseudoSample>& pseudo,
                                   const std::vector<TimeNs>& t_ns, const States& s,
                                   const RefineOptions& opt, RefineSummary* summary) {
  std::vector<Interval> out(t_ns.size() - 1);
  summary->num_imu_intervals_skipped = summary->num_dvl_intervals_skipped = 0;
  const TimeNs imu_gap = seconds_to_ns(opt.max_imu_gap_s);
  const TimeNs pseudo_gap = seconds_to_ns(std::min(opt.max_imu_gap_s, opt.reconcile.max_dvl_gap_s));
  const Eigen::Matrix3d R_imu_dvl = block_rotation(s.q_imu_dvl());
  for (size_t k = 0; k + 1 < t_ns.size(); ++k) {
    if (opt.use_imu) {
      auto pre = std::make_shared<ImuPreintegration>(vec(s.bg(k)), vec(s.ba(k)), opt.imu_noise);
      const bool ok = for_each_hold_segment(
          in.imu, t_ns[k], t_ns[k + 1], imu_gap,
          [&](const ImuSample& m, double dt) { pre->integrate(m.gyro_radps, m.accel_mps2, dt); });
      if (ok)
        out[k].imu = pre;
      else
        ++summary->num_imu_intervals_skipped;
    }
    if (opt.use_dvl && !in.dvl.empty()) {
      auto pre =
          std::make_shared<DvlPreintegration>(vec(s.bg(k)), vec(s.bv(k)), *s.scale(), R_imu_dvl,
                                              opt.dvl_noise, opt.imu_noise.gyro_noise_density);
      const bool ok = for_each_hold_segment(
          pseudo, t_ns[k], t_ns[k + 1], pseudo_gap, [&](const PseudoSample& m, double dt) {
            pre->integrate(m.gyro_radps, m.velocity_dvl_mps, dt, m.dvl_period_s);
          });
      if (ok)
        out[k].dvl = pre;
      else
        ++summary->num_dvl_intervals_skipped;
    }
  }
  return out;
}

class GraphBuilder {
 public:
  GraphBuilder(States* s, const RefineOptions& opt) : s_(s), opt_(opt) {
    ceres::Problem::Options po;
    po.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    po.enable_fast_removal = false;
    problem_ = std::make_unique<ceres::Problem>(po);
  }

  ceres::Problem& problem() { return *problem_; }

  void add_blocks() {
    for (size_t k = 0; k < s_->keyframes(); ++k) {
      problem_->AddParameterBlock(s_->pose(k), 7, &pose_manifold_);
      for (double* b : {s_->vel(k), s_->bg(k), s_->ba(k), s_->bv(k)}) {
        problem_->AddParameterBlock(b, 3);
      }
    }
    if (opt_.use_map_anchors) {
      for (size_t k = 0; k < s_->keyframes(); ++k) problem_->AddParameterBlock(s_->drift(k), 3);
      problem_->SetParameterBlockConstant(s_->drift(0));  // keyframe 0 is the gauge
    }
    problem_->AddParameterBlock(s_->scale(), 1);
    problem_->AddParameterBlock(s_->q_imu_dvl(), 4, &rotation_manifold_);
  }

  // r_0 of Eq. (3): the first keyframe's pose (the gauge), velocity and biases. With MAP
  // anchors the pose part is the first keyframe's anchor instead (add_map_anchors): its
  // recorded pose is as noisy as the others, and the anchors together fix the gauge.
  void add_prior(const Pose3& T0) {
    add_vector_prior(s_->vel(0), opt_.prior_sigma_velocity_mps);
    add_vector_prior(s_->bg(0), opt_.prior_sigma_gyro_bias_radps);
    add_vector_prior(s_->ba(0), opt_.prior_sigma_accel_bias_mps2);
    add_vector_prior(s_->bv(0), opt_.prior_sigma_dvl_bias_mps);
    if (opt_.use_map_anchors || gnss_gauge_) return;
    Matrix6d S = Matrix6d::Zero();
    S.diagonal().head<3>().setConstant(1.0 / opt_.prior_sigma_position_m);
    S.diagonal().tail<3>().setConstant(1.0 / opt_.prior_sigma_rotation_rad);
    problem_->AddResidualBlock(new PosePriorFactor(T0, S), nullptr, s_->pose(0));
  }

  // Loop closures are robustified (a wrong one must not wreck the map); odometry is not.
  void add_edges(const std::vector<KeyframeEdge>& edges, bool robust) {
    for (const KeyframeEdge& e : edges) {
      ceres::LossFunction* loss = nullptr;
      if (robust && opt_.loop_closure_cauchy_scale > 0) {
        loss = new ceres::CauchyLoss(opt_.loop_closure_cauchy_scale);
      }
      problem_->AddResidualBlock(new RelativePoseFactor(e.T_i_j, e.sqrt_info), loss, s_->pose(e.i),
                                 s_->pose(e.j));
    }
  }

  // MAP anchors on every keyframe (keyframe 0's drift is zero) and the drift's random walk, in
  // the IMU frame: T_map[k] = T_world_body,map T_body_imu, noise with rotation in IMU axes.
  // The drift walks only over intervals whose odometry is degenerate (where the online SLAM,
  // using the same scan matching, had to dead reckon) and where a factor measures displacement
  // (D_ij, or an odometry edge kept): against the IMU alone, whose velocity and accelerometer
  // bias are free, a drift of the MAP cannot be told from a bias, and fitting one would bend
  // the trajectory to the MAP's noise. Elsewhere the drift is held (its walk at the floor).
  void add_map_anchors(const std::vector<Pose3>& T_map, const MapPoseNoise& noise,
                       const std::vector<double>& path_m, const std::vector<bool>& walks) {
    Matrix6d S = Matrix6d::Zero();
    S.topLeftCorner<3, 3>() = sqrt_information_from_covariance(noise.translation_covariance);
    S.bottomRightCorner<3, 3>() = sqrt_information_from_covariance(noise.rotation_covariance);
    const Eigen::Matrix3d floor =
        Eigen::Matrix3d::Identity() * std::pow(opt_.map_noise_estimate.min_drift_per_sqrt_m, 2);
    for (size_t k = 0; k < T_map.size(); ++k) {
      ceres::LossFunction* loss = nullptr;
      if (opt_.map_anchor_huber_scale > 0) loss = new ceres::HuberLoss(opt_.map_anchor_huber_scale);
      problem_->AddResidualBlock(new MapAnchorFactor(T_map[k], S), loss, s_->pose(k), s_->drift(k));
      if (k == 0) continue;
      // A keyframe that did not move still gets a finite step (1 mm of path).
      const double step_m = std::max(1e-3, path_m[k] - path_m[k - 1]);
      const Eigen::Matrix3d Q = walks[k] ? noise.drift_covariance_per_m : floor;
      problem_->AddResidualBlock(
          new VectorRandomWalkFactor(sqrt_information_from_covariance(Q * step_m)), nullptr,
          s_->drift(k - 1), s_->drift(k));
    }
  }

  // I_ij, D_ij and the random walks of Eq. (6)-(7) for every interval.
  // Returns whether I_ij kept its position residual next to a D_ij.
  bool add_interval(size_t k, const Interval& iv, const Eigen::Vector3d& g, double dt_s,
                    bool degenerate) {
    const size_t j = k + 1;
    const bool drop_position = opt_.drop_imu_position_residual_with_dvl &&
                               !(degenerate && opt_.imu_position_when_degenerate);
    if (iv.imu) {
      const bool with_position = !(iv.dvl && drop_position);
      problem_->AddResidualBlock(
          new ImuFactor(iv.imu, g, imu_sqrt_information(*iv.imu, with_position)), nullptr,
          s_->pose(k), s_->vel(k), s_->bg(k), s_->ba(k), s_->pose(j), s_->vel(j));
      vel_used_[k] = vel_used_[j] = true;
    }
    if (iv.dvl) {
      problem_->AddResidualBlock(
          new DvlFactor(iv.dvl, t_imu_dvl_,
                        sqrt_information_from_covariance(iv.dvl->position_covariance())),
          nullptr, s_->pose(k), s_->bg(k), s_->bv(k), s_->pose(j), s_->scale(), s_->q_imu_dvl());
      ++num_dvl_;
    }
    problem_->AddResidualBlock(new BiasRandomWalkFactor(opt_.imu_noise.gyro_random_walk, dt_s),
                               nullptr, s_->bg(k), s_->bg(j));
    problem_->AddResidualBlock(new BiasRandomWalkFactor(opt_.imu_noise.accel_random_walk, dt_s),
                               nullptr, s_->ba(k), s_->ba(j));
    const double speed = iv.dvl ? iv.dvl->mean_speed_mps() : 0.0;
    problem_->AddResidualBlock(
        new BiasRandomWalkFactor(opt_.dvl_noise.bias_random_walk(speed), dt_s), nullptr, s_->bv(k),
        s_->bv(j));
    return iv.imu && iv.dvl && !drop_position;
  }

  // Calibration priors (beyond the paper) and the blocks held constant.
  void finish(const std::vector<KeyframeEstimate>& kf, const Eigen::Matrix3d& R_imu_dvl_prior) {
    ceres::Problem& p = *problem_;
    Eigen::Matrix<double, 1, 1> A;
    A(0, 0) = 1.0 / opt_.dvl_scale_prior_sigma;
    Eigen::VectorXd b(1);
    b(0) = opt_.dvl_scale_initial;
    p.AddResidualBlock(new ceres::NormalPrior(A, b), nullptr, s_->scale());
    p.AddResidualBlock(
        new RotationPriorFactor(R_imu_dvl_prior,
                                Eigen::Matrix3d::Identity() / opt_.dvl_rotation_prior_sigma_rad),
        nullptr, s_->q_imu_dvl());
    if (!opt_.estimate_dvl_scale || num_dvl_ == 0)
      p.SetParameterBlockConstant(s_->scale());
    else
      p.SetParameterLowerBound(s_->scale(), 0, 0.5);
    if (!opt_.estimate_dvl_rotation || num_dvl_ == 0) {
      p.SetParameterBlockConstant(s_->q_imu_dvl());
    }
    for (size_t k = 0; k < kf.size(); ++k) {
      if (!vel_used_[k]) p.SetParameterBlockConstant(s_->vel(k));
      if (!opt_.use_imu) p.SetParameterBlockConstant(s_->ba(k));
      if (!opt_.use_imu && num_dvl_ == 0) p.SetParameterBlockConstant(s_->bg(k));
      if (num_dvl_ == 0) p.SetParameterBlockConstant(s_->bv(k));
      if (kf[k].biases_zeroed) {  // Sec. IV-B: unobservable during degeneracy, set to zero
        for (double* b : {s_->bg(k), s_->ba(k), s_->bv(k)}) p.SetParameterBlockConstant(b);
      }
    }
  }

  void set_lever_arm(const Eigen::Vector3d& t_imu_dvl) { t_imu_dvl_ = t_imu_dvl; }
  void reset_usage(size_t n) {
    vel_used_.assign(n, false);
    num_dvl_ = 0;
  }
  int num_dvl() const { return num_dvl_; }
  bool gnss_gauge_ = false;  // GNSS fixes fix the gauge: no pose prior

 private:
  void add_vector_prior(double* b, double sigma) {
    const Eigen::Matrix3d A = Eigen::Matrix3d::Identity() / sigma;
    const Eigen::VectorXd mean = vec(b);
    problem_->AddResidualBlock(new ceres::NormalPrior(A, mean), nullptr, b);
  }

  States* s_;
  const RefineOptions& opt_;
  std::unique_ptr<ceres::Problem> problem_;
  PoseManifold pose_manifold_;
  RotationManifold rotation_manifold_;
  Eigen::Vector3d t_imu_dvl_ = Eigen::Vector3d::Zero();
  std::vector<bool> vel_used_;
  int num_dvl_ = 0;
};

// ---- Step 6: covariances --------------------------------------------------------------------

struct Covariances {
  std::vector<Matrix6d> pose;
  std::vector<Eigen::Matrix3d> bg, ba, bv;
  double scale_var = 0.0;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Zero();
};

bool compute_covariances(ceres::Problem& problem, States& s, bool keyframes, int num_threads,
                         Covariances* out) {
  const size_t n = s.keyframes();
  out->pose.assign(n, Matrix6d::Zero());
  out->bg.assign(n, Eigen::Matrix3d::Zero());
  out->ba = out->bv = out->bg;
  std::vector<std::pair<const double*, const double*>> blocks;
  auto want = [&](const double* b) {
    if (!problem.IsParameterBlockConstant(const_cast<double*>(b))) blocks.emplace_back(b, b);
  };
  for (size_t k = 0; k < n && keyframes; ++k) {
    want(s.pose(k));
    want(s.bg(k));
    want(s.ba(k));
    want(s.bv(k));
  }
  want(s.scale());
  want(s.q_imu_dvl());
  ceres::Covariance::Options co;
  co.num_threads = num_threads;
  co.algorithm_type = ceres::SPARSE_QR;
  ceres::Covariance cov(co);
  if (!cov.Compute(blocks, &problem)) return false;
  auto get3 = [&](const double* b, Eigen::Matrix3d* m) {
    if (problem.IsParameterBlockConstant(const_cast<double*>(b))) return;
    Eigen::Matrix<double, 3, 3, Eigen::RowMajor> r;
    cov.GetCovarianceBlockInTangentSpace(b, b, r.data());
    *m = r;
  };
  for (size_t k = 0; k < n && keyframes; ++k) {
    if (!problem.IsParameterBlockConstant(s.pose(k))) {
      Eigen::Matrix<double, 6, 6, Eigen::RowMajor> r;
      cov.GetCovarianceBlockInTangentSpace(s.pose(k), s.pose(k), r.data());
      out->pose[k] = r;
    }
    get3(s.bg(k), &out->bg[k]);
    get3(s.ba(k), &out->ba[k]);
    get3(s.bv(k), &out->bv[k]);
  }
  if (!problem.IsParameterBlockConstant(s.scale())) {
    cov.GetCovarianceBlockInTangentSpace(s.scale(), s.scale(), &out->scale_var);
  }
  get3(s.q_imu_dvl(), &out->rotation);
  return true;
}

// Covariance of T_world_body = T_world_imu T_imu_body from that of T_world_imu (both in the
// [delta p world, delta phi body] tangent): dphi_b = R_ib^T dphi, dp_b = dp - R_wi (t_ib)^ dphi.
Matrix6d body_pose_covariance(const Matrix6d& cov_imu, const Pose3& T_world_imu,
                              const Pose3& T_imu_body) {
  Matrix6d J = Matrix6d::Identity();
  J.block<3, 3>(0, 3) = -T_world_imu.linear() * hat(T_imu_body.translation());
  J.block<3, 3>(3, 3) = T_imu_body.linear().transpose();
  return J * cov_imu * J.transpose();
}

}  // namespace

Trajectory RefineResult::trajectory() const {
  Trajectory out;
  out.reserve(keyframes.size());
  for (const KeyframeEstimate& k : keyframes) out.push_back({k.t_ns, k.T_world_body});
  return out;
}

RefineResult refine_trajectory(const RefineInput& in, const RefineOptions& opt) {
  const Clock::time_point t_start = Clock::now();
  use_aligned_suitesparse_memory();  // the same bits wherever its fronts land
  RefineResult result;
  RefineSummary& summary = result.summary;

  // 1. Inputs, converted to the IMU frame B.
  validate_keyframes(in.keyframes);
  validate_imu_samples(in.imu);
  validate_dvl_samples(in.dvl);
  if (!in.T_body_imu.matrix().allFinite() || !in.T_body_dvl.matrix().allFinite()) {
    throw std::invalid_argument("T_body_imu / T_body_dvl: not finite");
  }
  const size_t n = in.keyframes.size();
  std::vector<TimeNs> t_ns(n);
  std::vector<Pose3> T_world_imu(n);
  std::vector<KeyframeEstimate>& kf = result.keyframes;
  kf.resize(n);
  for (size_t k = 0; k < n; ++k) {
    t_ns[k] = kf[k].t_ns = in.keyframes[k].t_ns;
    T_world_imu[k] = in.keyframes[k].T_world_body * in.T_body_imu;
  }
  const Pose3 T_imu_dvl = in.T_body_imu.inverse() * in.T_body_dvl;

  // 2. Odometry edges with per-keyframe degeneracy, and loop closures.
  const std::vector<KeyframeEdge> odometry = odometry_edges(in, opt, t_ns, &kf);
  const std::vector<KeyframeEdge> loops = loop_edges(in, opt, t_ns);
  // Biases are unobservable in degeneracy unless I_ij's position residual ties the velocity
  // states to the DVL there (imu_position_when_degenerate).
  // MAP anchors observe every keyframe's position, which makes them observable as well.
  const bool biases_observable_when_degenerate =
      opt.use_map_anchors ||
      (opt.use_imu && opt.use_dvl && !in.dvl.empty() &&
       (opt.imu_position_when_degenerate || !opt.drop_imu_position_residual_with_dvl));
  for (KeyframeEstimate& k : kf) {
    k.biases_zeroed =
        k.degenerate && opt.zero_biases_when_degenerate && !biases_observable_when_degenerate;
    summary.num_degenerate_keyframes += k.degenerate ? 1 : 0;
  }

  // 3. Algorithm 1: pseudosensor measurements.
  std::vector<PseudoSample> pseudo;
  if (opt.use_dvl && !in.dvl.empty()) {
    pseudo = reconcile_dvl_imu(in.dvl, in.imu, T_imu_dvl.linear(), opt.reconcile);
  }
  summary.num_pseudo_samples = pseudo.size();

  // 4. Initial states.
  States s = initial_states(T_world_imu, t_ns, pseudo, T_imu_dvl, opt);
  const Eigen::Vector3d g(0.0, 0.0, -opt.gravity_mps2);

  // MAP anchors: the recorded poses in the IMU frame, and their noise with rotation in IMU axes.
  const Eigen::Matrix3d R_body_imu = in.T_body_imu.linear();
  const std::vector<double> path_m = path_lengths(T_world_imu);
  // The MAP's drift path: the path travelled over keyframes whose odometry is degenerate.
  for (size_t k = 1; k < n; ++k)
    kf[k].map_drift_path_m =
        kf[k - 1].map_drift_path_m + (kf[k].degenerate ? path_m[k] - path_m[k - 1] : 0.0);
  MapPoseNoise map_noise = opt.map_noise;
  map_noise.rotation_covariance =
      R_body_imu.transpose() * opt.map_noise.rotation_covariance * R_body_imu;
  if (opt.use_map_anchors && opt.estimate_map_noise && n < 3) {
    throw std::invalid_argument("keyframes: estimating the MAP noise needs at least 3, got " +
                                std::to_string(n));
  }

  // GNSS fixes between the keyframes, and the antenna's lever arm in the IMU frame.
  const std::vector<GnssPlacement> gnss_at = place_gnss_fixes(in.gnss, t_ns, opt.gnss);
  const Eigen::Vector3d lever_imu_gnss = (in.T_body_imu.inverse() * in.T_body_gnss).translation();
  const long gnss_placed = std::count_if(gnss_at.begin(), gnss_at.end(),
                                         [](const GnssPlacement& p) { return p.k >= 0; });

  // 5. Preintegrate at the current estimates, build Eq. (3) extended, solve; repeat.
  std::unique_ptr<GraphBuilder> graph;
  const int passes = std::max(1, opt.relinearization_passes);
  for (int pass = 0; pass < passes; ++pass) {
    for (size_t k = 0; k < n; ++k) {
      if (kf[k].biases_zeroed)
        for (double* b : {s.bg(k), s.ba(k), s.bv(k)}) std::fill(b, b + 3, 0.0);
    }
    const std::vector<Interval> intervals = preintegrate(in, pseudo, t_ns, s, opt, &summary);
    graph = std::make_unique<GraphBuilder>(&s, opt);
    graph->reset_usage(n);
    graph->set_lever_arm(T_imu_dvl.translation());
    graph->add_blocks();
    graph->gnss_gauge_ = gnss_placed >= opt.min_gnss_fixes_for_gauge;
    graph->add_prior(T_world_imu[0]);
    graph->add_edges(odometry, /*robust=*/false);
    graph->add_edges(loops, /*robust=*/true);
    summary.num_imu_factors = summary.num_dvl_factors = 0;
    for (size_t k = 0; k + 1 < n; ++k) {
      kf[k + 1].imu_position_with_dvl = graph->add_interval(
          k, intervals[k], g, ns_to_seconds(t_ns[k + 1] - t_ns[k]), kf[k + 1].degenerate);
      kf[k + 1].has_imu_factor = intervals[k].imu != nullptr;
      kf[k + 1].has_dvl_factor = intervals[k].dvl != nullptr;
      summary.num_imu_factors += intervals[k].imu ? 1 : 0;
      summary.num_dvl_factors += intervals[k].dvl ? 1 : 0;
    }
    if (opt.use_map_anchors) {
      std::vector<bool> walks(n, false);
      for (size_t k = 1; k < n; ++k)
        walks[k] = kf[k].degenerate && (kf[k].has_dvl_factor || kf[k].has_odometry_factor);
      graph->add_map_anchors(T_world_imu, map_noise, path_m, walks);
    }
    if (gnss_placed > 0) {  // gated against the previous pass (the first: Cauchy, no gate)
      result.gnss_counts = add_gnss_factors(
          graph->problem(), in.gnss, gnss_at, [&](size_t k) { return s.pose(k); }, lever_imu_gnss,
          opt.gnss, /*gate=*/pass > 0 || passes == 1, &result.gnss_use);
    }
    graph->finish(kf, T_imu_dvl.linear());

    ceres::Solver::Options so;
    so.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
    so.max_num_iterations = opt.max_iterations;
    // One thread: on more, Ceres sums the residual blocks' cost and gradient per thread, in
    // the order the threads take them, so the reported costs (and, near a tolerance, the
    // iterations) would change with the thread count and the machine's load.
    so.num_threads = 1;
    so.logging_type = ceres::SILENT;
    ceres::Solver::Summary ceres_summary;
    const Clock::time_point t_solve = Clock::now();
    ceres::Solve(so, &graph->problem(), &ceres_summary);
    summary.solve_time_s += seconds_since(t_solve);
    if (pass == 0) summary.initial_cost = ceres_summary.initial_cost;
    summary.final_cost = ceres_summary.final_cost;
    summary.iterations += static_cast<int>(ceres_summary.iterations.size());
    summary.converged = ceres_summary.termination_type == ceres::CONVERGENCE;
    summary.ceres_report = ceres_summary.BriefReport();
    if (opt.use_map_anchors && opt.estimate_map_noise && pass + 1 < passes) {
      std::vector<Pose3> estimate(n);
      for (size_t k = 0; k < n; ++k) estimate[k] = get_pose_block(s.pose(k));
      std::vector<double> drift_path(n);
      for (size_t k = 0; k < n; ++k) drift_path[k] = kf[k].map_drift_path_m;
      map_noise =
          estimate_map_pose_noise(T_world_imu, estimate, drift_path, opt.map_noise_estimate);
      result.map_noise_estimated = true;
    }
  }
  result.map_noise = map_noise;
  result.map_noise.rotation_covariance =
      R_body_imu * map_noise.rotation_covariance * R_body_imu.transpose();
  summary.num_keyframes = static_cast<int>(n);
  summary.num_odometry_factors = static_cast<int>(odometry.size());
  summary.num_loop_closures = static_cast<int>(loops.size());
  summary.num_map_anchors = opt.use_map_anchors ? static_cast<int>(n) : 0;

  // 6. Covariances of the last pass's problem.
  Covariances cov;
  if (opt.covariances != CovarianceScope::kNone) {
    const Clock::time_point t_cov = Clock::now();
    summary.covariance_ok = compute_covariances(
        graph->problem(), s, opt.covariances == CovarianceScope::kAll, opt.num_threads, &cov);
    summary.covariance_time_s = seconds_since(t_cov);
  }

  // 7. Back to the body frame.
  const Pose3 T_imu_body = in.T_body_imu.inverse();
  for (size_t k = 0; k < n; ++k) {
    const Pose3 T_wi = get_pose_block(s.pose(k));
    kf[k].T_world_body = T_wi * T_imu_body;
    kf[k].velocity_imu_world_mps = vec(s.vel(k));
    kf[k].bias_gyro_radps = vec(s.bg(k));
    kf[k].bias_accel_mps2 = vec(s.ba(k));
    kf[k].bias_dvl_mps = vec(s.bv(k));
    if (summary.covariance_ok && opt.covariances == CovarianceScope::kAll) {
      kf[k].pose_covariance = body_pose_covariance(cov.pose[k], T_wi, T_imu_body);
      kf[k].bias_gyro_covariance = cov.bg[k];
      kf[k].bias_accel_covariance = cov.ba[k];
      kf[k].bias_dvl_covariance = cov.bv[k];
    }
  }
  result.dvl_scale = *s.scale();
  result.dvl_scale_sigma = std::sqrt(std::max(0.0, cov.scale_var));
  result.q_body_dvl = Eigen::Quaterniond(in.T_body_imu.linear() * block_rotation(s.q_imu_dvl()));
  result.dvl_rotation_covariance = cov.rotation;  // R_body_imu R Exp(d) = R_body_dvl Exp(d)
  summary.total_time_s = seconds_since(t_start);
  return result;
}

}  // namespace keel::slam
