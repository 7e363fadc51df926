#include "worker/ba/ba_graph.h"

#include <ceres/ceres.h>
#include <ceres/covariance.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <ctime>
#include <limits>
#include <memory>
#include <stdexcept>

#include "worker/ba/odometry_factor.h"
#include "worker/ba/pose_block.h"
#include "worker/ba/prior_factors.h"
#include "worker/ba/reprojection_factors.h"
#include "worker/ba/rig_geometry.h"
#include "worker/ba/surface_factor.h"

namespace keel::ba {
namespace {

// Fig. 16: the fraction of lambda = 1 after every iteration. The surface factors write their
// labels whenever Ceres evaluates Jacobians, which it does exactly at accepted states, so the
// slots describe the current state when the callback runs.
class LabelFractionCallback : public ceres::IterationCallback {
 public:
  LabelFractionCallback(const std::vector<uint8_t>& labels, std::vector<double>& fractions)
      : labels_(labels), fractions_(fractions) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
    size_t on = 0;
    for (uint8_t l : labels_) on += l;
    fractions_.push_back(labels_.empty() ? 0.0 : double(on) / double(labels_.size()));
    return ceres::SOLVER_CONTINUE;
  }

 private:
  const std::vector<uint8_t>& labels_;
  std::vector<double>& fractions_;
};

// Every parameter block of a BaGraph in one buffer, in the order the blocks are added to the
// problem: per keyframe the pose x_gv_i (7) and the servo angle (1), then x_gM (7), x_sc_T (7)
// and the landmarks (3 each). Ceres orders parameter blocks by their address where the problem
// leaves it free: the Schur ordering's groups are std::set<double*> (the reduced camera
// system's columns follow it) and Covariance sorts the blocks by pointer. Separate heap
// allocations change their relative order from run to run, and with it the solution (1e-11)
// and x_gM's sigma (1e-15); one buffer makes address order = insertion order.
class ParameterBuffer {
 public:
  ParameterBuffer(size_t keyframes, size_t landmarks)
      : num_keyframes_(keyframes),
        num_landmarks_(landmarks),
        values_(keyframes * kKeyframeStride + 2 * kPoseBlockSize + landmarks * 3, 0.0) {}

  size_t keyframes() const { return num_keyframes_; }
  size_t landmarks() const { return num_landmarks_; }
  double* pose(size_t i) { return &values_[i * kKeyframeStride]; }
  const double* pose(size_t i) const { return &values_[i * kKeyframeStride]; }
  double* servo(size_t i) { return pose(i) + kPoseBlockSize; }
  const double* servo(size_t i) const { return pose(i) + kPoseBlockSize; }
  double* model() { return &values_[num_keyframes_ * kKeyframeStride]; }
  const double* model() const { return &values_[num_keyframes_ * kKeyframeStride]; }
  double* extrinsic() { return model() + kPoseBlockSize; }
  const double* extrinsic() const { return model() + kPoseBlockSize; }
  double* landmark(size_t k) { return extrinsic() + kPoseBlockSize + 3 * k; }
  const double* landmark(size_t k) const { return extrinsic() + kPoseBlockSize + 3 * k; }

  std::vector<double> servo_angles() const {
    std::vector<double> out;
    for (size_t i = 0; i < num_keyframes_; ++i) out.push_back(*servo(i));
    return out;
  }
  std::vector<std::array<double, 3>> landmark_points() const {
    std::vector<std::array<double, 3>> out;
    for (size_t k = 0; k < num_landmarks_; ++k) {
      const double* l = landmark(k);
      out.push_back({l[0], l[1], l[2]});
    }
    return out;
  }

 private:
  static constexpr size_t kKeyframeStride = kPoseBlockSize + 1;
  size_t num_keyframes_, num_landmarks_;
  std::vector<double> values_;  // sized once: Ceres keeps pointers into it
};

// Ceres's solves run on one thread. With more, each thread sums the cost and gradient of the
// residual blocks it happened to take, and the Schur eliminator adds each landmark's share into
// the reduced camera system under a lock, in the order the threads get there: the sums differ
// in their last bits from run to run, and so did every BA output (1e-11 relative on keel-sim
// hauv-hull). BaOptions::num_threads still splits the mesh queries (one slot per query) and
// the covariance's columns (each solved on its own), which give the same bits on any number of
// threads.
constexpr int kCeresSolverThreads = 1;

void set_pose_block(double* block, const Pose3& T) {
  const PoseBlock b = to_pose_block(T);
  std::copy(b.begin(), b.end(), block);
}

PoseBlock pose_block_at(const double* block) {
  PoseBlock b;
  std::copy(block, block + kPoseBlockSize, b.begin());
  return b;
}

class BaGraph {
 public:
  // model_free: the online-SLAM graph (no x_gM, no DVL raycasts, no surface factors).
  BaGraph(const BaProblem& problem, const MeshQuery& mesh, const BaInitialState& initial,
          BaMode mode, const BaOptions& options, bool model_free = false)
      : problem_(problem),
        mesh_(mesh),
        initial_(initial),
        mode_(mode),
        model_free_(model_free),
        options_(options),
        mount_(servo_mount(problem.rig)),
        pose_manifold_(make_pose_manifold()),
        reprojection_loss_(std::make_unique<ceres::HuberLoss>(options.reprojection_huber)),
        dvl_loss_(std::make_unique<ceres::HuberLoss>(options.dvl_huber)),
        x_(initial.T_world_vehicle.size(), initial.landmarks_world.size()),
        ceres_problem_(problem_options()) {
    init_variables();
    add_priors();
    add_odometry();
    add_camera_factors();
    if (model_free_) return;
    add_dvl_factors();
    if (mode_ != BaMode::kNaive) add_surface_factors();
  }

  BaModeResult solve() {
    BaModeResult result;
    result.mode = mode_;
    if (!model_free_) result.dvl_residuals_initial = residuals_now();
    ceres::Solver::Options solver = solver_options();
    LabelFractionCallback callback(labels_, result.lambda1_fraction_per_iteration);
    if (!labels_.empty()) solver.callbacks.push_back(&callback);
    ceres::Solver::Summary summary;
    const auto start = std::chrono::steady_clock::now();
    const std::clock_t cpu_start = std::clock();
    ceres::Solve(solver, &ceres_problem_, &summary);
    result.solve_time_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    result.solve_cpu_s = double(std::clock() - cpu_start) / CLOCKS_PER_SEC;
    result.iterations = summary.num_successful_steps + summary.num_unsuccessful_steps;
    result.unsuccessful_steps = summary.num_unsuccessful_steps;
    // Ceres reports a rejected step's candidate cost; the curve keeps the state's cost.
    for (const ceres::IterationSummary& it : summary.iterations) {
      const bool kept = !result.cost_per_iteration.empty() && !it.step_is_successful;
      result.cost_per_iteration.push_back(kept ? result.cost_per_iteration.back() : it.cost);
    }
    result.initial_cost = summary.initial_cost;
    result.final_cost = summary.final_cost;
    result.converged = summary.termination_type == ceres::CONVERGENCE;
    result.termination = summary.message;
    read_back(result);
    if (!model_free_) {
      result.dvl_residuals_final = residuals_now();
      result.model_translation_sigma_m = model_translation_sigma(result.T_world_model);
    }
    return result;
  }

 private:
  static ceres::Problem::Options problem_options() {
    ceres::Problem::Options o;
    o.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    o.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    return o;
  }

  void add_pose_block(double* block) {
    ceres_problem_.AddParameterBlock(block, kPoseBlockSize, pose_manifold_.get());
  }

  void init_variables() {
    for (size_t i = 0; i < x_.keyframes(); ++i) {
      set_pose_block(x_.pose(i), initial_.T_world_vehicle[i]);
      add_pose_block(x_.pose(i));
      *x_.servo(i) = initial_.servo_angle_rad[i];
      ceres_problem_.AddParameterBlock(x_.servo(i), 1);
    }
    set_pose_block(x_.model(), initial_.T_world_model);
    set_pose_block(x_.extrinsic(), initial_.T_servo_camera);
    if (!model_free_) add_pose_block(x_.model());
    add_pose_block(x_.extrinsic());
    for (size_t k = 0; k < x_.landmarks(); ++k) {
      const Eigen::Vector3d& l = initial_.landmarks_world[k];
      std::copy(l.data(), l.data() + 3, x_.landmark(k));
      ceres_problem_.AddParameterBlock(x_.landmark(k), 3);
    }
  }

  void add_priors() {
    const BaOptions& o = options_;
    // Eq. (8): x_gM from GICP with Sigma = I_6; the first pose (gauge); x_sc_T.
    if (!model_free_) {
      ceres_problem_.AddResidualBlock(
          make_pose_prior_factor(initial_.T_world_model, o.model_prior_sigma_m,
                                 o.model_prior_sigma_rad),
          nullptr, x_.model());
    }
    ceres_problem_.AddResidualBlock(
        make_pose_prior_factor(initial_.T_world_vehicle.front(), o.first_pose_prior_sigma_m,
                               o.first_pose_prior_sigma_rad),
        nullptr, x_.pose(0));
    ceres_problem_.AddResidualBlock(
        make_pose_prior_factor(initial_.T_servo_camera, o.extrinsic_prior_sigma_m,
                               o.extrinsic_prior_sigma_rad),
        nullptr, x_.extrinsic());
    for (size_t i = 0; i < x_.keyframes(); ++i) {
      const BaKeyframe& k = problem_.keyframes[i];
      const DepthPitchRoll zpr =
          k.depth_pitch_roll ? *k.depth_pitch_roll : depth_pitch_roll_of(k.T_world_vehicle);
      ceres_problem_.AddResidualBlock(  // Eq. (9)
          make_depth_pitch_roll_factor(zpr, o.depth_sigma_m, o.pitch_sigma_rad, o.roll_sigma_rad),
          nullptr, x_.pose(i));
      ceres_problem_.AddResidualBlock(  // Eq. (10)
          make_servo_angle_factor(k.servo_angle_rad, o.servo_sigma_rad), nullptr, x_.servo(i));
    }
  }

  void add_odometry() {
    for (const BaOdometry& odo : problem_.odometry) {
      const double dt_s =
          ns_to_seconds(problem_.keyframes[odo.to].t_ns - problem_.keyframes[odo.from].t_ns);
      const OdometrySigmas sigmas =
          odometry_sigmas(dt_s, options_.odometry_sigma_m_per_s, options_.odometry_sigma_rad_per_s,
                          options_.odometry_min_sigma_m, options_.odometry_min_sigma_rad);
      ceres_problem_.AddResidualBlock(make_odometry_factor(odo.T_from_to, sigmas), nullptr,
                                      x_.pose(odo.from), x_.pose(odo.to));
    }
  }

  // Eq. (12) for a stereo observation, Eq. (13) for a monocular one.
  ceres::CostFunction* reprojection_factor(const FeatureObservation& obs) const {
    const BaRig& rig = problem_.rig;
    return obs.pixel_bottom && rig.camera_bottom
               ? make_stereo_factor(rig.camera_top, *rig.camera_bottom, rig.T_top_bottom, mount_,
                                    obs.pixel, *obs.pixel_bottom, options_.pixel_sigma)
               : make_monocular_factor(rig.camera_top, mount_, obs.pixel, options_.pixel_sigma);
  }

  void add_camera_factors() {
    for (size_t k = 0; k < initial_.tracks.size(); ++k) {
      for (const FeatureObservation& obs : initial_.tracks[k].observations) {
        ceres_problem_.AddResidualBlock(reprojection_factor(obs), reprojection_loss_.get(),
                                        x_.pose(obs.keyframe), x_.servo(obs.keyframe),
                                        x_.extrinsic(), x_.landmark(k));
      }
    }
  }

  void add_dvl_factors() {
    for (size_t b = 0; b < initial_.beams.size(); ++b) {
      const int i = initial_.beam_keyframe[b];
      ceres_problem_.AddResidualBlock(  // Eq. (14)
          make_dvl_raycast_factor(mesh_, mount_, initial_.beams[b], options_.dvl_sigma_m,
                                  options_.dvl_max_range_m, options_.dvl_gate_m,
                                  options_.dvl_range_normal),
          dvl_loss_.get(), x_.pose(i), x_.servo(i), x_.model());
    }
  }

  void add_surface_factors() {
    const MaxMixture mixture{options_.sigma0_m, options_.sigma1_m};
    const SurfaceMode mode =
        mode_ == BaMode::kGeva ? SurfaceMode::kOnModel : SurfaceMode::kMaxMixture;
    labels_.assign(x_.landmarks(), 0);
    for (size_t k = 0; k < x_.landmarks(); ++k) {
      ceres_problem_.AddResidualBlock(  // Eq. (4)-(7)
          make_surface_factor(mesh_, mixture, mode, options_.surface_offset_m, &labels_[k]),
          nullptr, x_.model(), x_.landmark(k));
    }
  }

  ceres::Solver::Options solver_options() {
    ceres::Solver::Options s;
    s.max_num_iterations = options_.max_iterations;
    s.num_threads = kCeresSolverThreads;
    s.function_tolerance = options_.function_tolerance;
    s.gradient_tolerance = options_.gradient_tolerance;
    s.parameter_tolerance = options_.parameter_tolerance;
    s.logging_type = ceres::SILENT;
    if (options_.linear_solver == "sparse_schur") {
      s.linear_solver_type = ceres::SPARSE_SCHUR;
    } else if (options_.linear_solver == "iterative_schur") {
      s.linear_solver_type = ceres::ITERATIVE_SCHUR;
      s.preconditioner_type = ceres::SCHUR_JACOBI;
    } else if (options_.linear_solver == "dense_schur") {
      s.linear_solver_type = ceres::DENSE_SCHUR;
    } else {
      throw std::invalid_argument(
          "ba options: linear_solver: expected sparse_schur, "
          "iterative_schur or dense_schur, got '" +
          options_.linear_solver + "'");
    }
    // Schur elimination: landmarks first, then every other variable.
    auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
    for (size_t k = 0; k < x_.landmarks(); ++k) ordering->AddElementToGroup(x_.landmark(k), 0);
    for (size_t i = 0; i < x_.keyframes(); ++i) {
      ordering->AddElementToGroup(x_.pose(i), 1);
      ordering->AddElementToGroup(x_.servo(i), 1);
    }
    if (!model_free_) ordering->AddElementToGroup(x_.model(), 1);
    ordering->AddElementToGroup(x_.extrinsic(), 1);
    s.linear_solver_ordering = ordering;
    return s;
  }

  // x_gM's translation standard deviations along the model frame's axes.
  std::vector<double> model_translation_sigma(const Pose3& T_world_model) {
    ceres::Covariance::Options o;
    o.algorithm_type = ceres::SPARSE_QR;
    o.num_threads = options_.num_threads;
    ceres::Covariance covariance(o);
    const std::vector<std::pair<const double*, const double*>> block = {{x_.model(), x_.model()}};
    if (!covariance.Compute(block, &ceres_problem_)) return {};
    Eigen::Matrix<double, 6, 6, Eigen::RowMajor> tangent;
    if (!covariance.GetCovarianceBlockInTangentSpace(x_.model(), x_.model(), tangent.data()))
      return {};
    const Eigen::Vector3d sigma = translation_sigma_in_own_axes(tangent, T_world_model.linear());
    return {sigma.x(), sigma.y(), sigma.z()};
  }

  std::vector<Pose3> current_poses() const {
    std::vector<Pose3> out;
    for (size_t i = 0; i < x_.keyframes(); ++i) out.push_back(from_pose_block(x_.pose(i)));
    return out;
  }

  std::vector<DvlBeamResidual> residuals_now() const {
    return dvl_range_residuals(mesh_, mount_, initial_.beams, initial_.beam_keyframe,
                               current_poses(), x_.servo_angles(), from_pose_block(x_.model()),
                               options_.dvl_max_range_m);
  }

  void read_back(BaModeResult& result) const {
    result.T_world_vehicle = current_poses();
    result.servo_angle_rad = x_.servo_angles();
    result.T_world_model = from_pose_block(x_.model());
    result.T_servo_camera = from_pose_block(x_.extrinsic());
    for (size_t i = 0; i < x_.keyframes(); ++i) {
      result.T_world_camera.push_back(world_camera_pose(result.T_world_vehicle[i], *x_.servo(i),
                                                        mount_, result.T_servo_camera));
    }
    // h and lambda at the final state, Eq. (5) and (7).
    const Pose3 T_model_world = result.T_world_model.inverse();
    const std::vector<std::array<double, 3>> landmarks = x_.landmark_points();
    std::vector<Eigen::Vector3d> in_model;
    for (const auto& l : landmarks)
      in_model.push_back(T_model_world * Eigen::Vector3d(l[0], l[1], l[2]));
    // The model-free initialisation has no x_gM yet: no h, no labels.
    const std::vector<double> h = model_free_
                                      ? std::vector<double>(in_model.size(), 0.0)
                                      : mesh_.signed_distances(in_model, options_.num_threads);
    const VisionLandmarks vision_result = vision_only_landmarks();
    const std::vector<std::array<double, 3>>& vision = vision_result.points;
    std::vector<Eigen::Vector3d> vision_in_model;
    for (const auto& l : vision)
      vision_in_model.push_back(T_model_world * Eigen::Vector3d(l[0], l[1], l[2]));
    const std::vector<double> vision_h =
        vision == landmarks ? h : mesh_.signed_distances(vision_in_model, options_.num_threads);
    const MaxMixture mixture{options_.sigma0_m, options_.sigma1_m};
    for (size_t k = 0; k < landmarks.size(); ++k) {
      BaLandmark l;
      l.vision_position_world = Eigen::Vector3d(vision[k][0], vision[k][1], vision[k][2]);
      l.vision_signed_distance_m = vision_h[k];
      l.vision_sigma_m = vision_result.sigma_m[k];
      l.id = initial_.tracks[k].landmark_id;
      l.position_world = Eigen::Vector3d(landmarks[k][0], landmarks[k][1], landmarks[k][2]);
      l.signed_distance_m = h[k];
      l.lambda = mixture.label(options_.surface_offset_m - h[k]);
      for (const auto& obs : initial_.tracks[k].observations) l.keyframes.push_back(obs.keyframe);
      result.landmarks.push_back(std::move(l));
    }
  }

  // The landmarks placed by their reprojections alone, everything else held at the current
  // state (BaLandmark::vision_position_world), in a problem of their own starting from the
  // solution (naive's positions already are), and each one's sigma (vision_sigma_m).
  struct VisionLandmarks {
    std::vector<std::array<double, 3>> points;
    std::vector<double> sigma_m;
  };
  VisionLandmarks vision_only_landmarks() const {
    VisionLandmarks out{x_.landmark_points(), std::vector<double>(x_.landmarks(), 0.0)};
    if (model_free_ || out.points.empty()) return out;
    // Copies, the solution stays as it is. Only the landmarks vary here, and out.points is one
    // buffer: their address order (ParameterBuffer) is their index order.
    std::vector<PoseBlock> poses;
    for (size_t i = 0; i < x_.keyframes(); ++i) poses.push_back(pose_block_at(x_.pose(i)));
    std::vector<double> servo = x_.servo_angles();
    PoseBlock extrinsic = pose_block_at(x_.extrinsic());
    ceres::Problem problem(problem_options());
    std::vector<std::vector<ceres::ResidualBlockId>> blocks(out.points.size());
    for (size_t k = 0; k < initial_.tracks.size(); ++k) {
      for (const FeatureObservation& obs : initial_.tracks[k].observations) {
        blocks[k].push_back(problem.AddResidualBlock(
            reprojection_factor(obs), reprojection_loss_.get(), poses[obs.keyframe].data(),
            &servo[obs.keyframe], extrinsic.data(), out.points[k].data()));
      }
    }
    for (size_t i = 0; i < poses.size(); ++i) {
      if (problem.HasParameterBlock(poses[i].data()))
        problem.SetParameterBlockConstant(poses[i].data());
      if (problem.HasParameterBlock(&servo[i])) problem.SetParameterBlockConstant(&servo[i]);
    }
    if (problem.HasParameterBlock(extrinsic.data()))
      problem.SetParameterBlockConstant(extrinsic.data());
    if (mode_ != BaMode::kNaive) {
      ceres::Solver::Options s;
      s.max_num_iterations = options_.max_iterations;
      s.num_threads = kCeresSolverThreads;
      // The landmarks are independent problems summed: a relative tolerance on the sum would
      // stop while a feature whose depth few views constrain (each adds little cost) is still
      // far from its own minimum. Iterate until no landmark moves.
      s.function_tolerance = 1e-14;
      s.gradient_tolerance = 1e-14;
      s.parameter_tolerance = 1e-12;
      s.logging_type = ceres::SILENT;
      // Only landmarks vary: the normal equations are 3x3 blocks on the diagonal.
      s.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
      ceres::Solver::Summary summary;
      ceres::Solve(s, &problem, &summary);
    }
    for (size_t k = 0; k < out.points.size(); ++k)
      out.sigma_m[k] = position_sigma(problem, blocks[k]);
    return out;
  }

  // sqrt of the largest eigenvalue of (sum J^T J)^-1 over a landmark's whitened reprojections
  // (Gauss-Newton covariance at the minimum; the robust loss left out, as for inliers).
  static double position_sigma(const ceres::Problem& problem,
                               const std::vector<ceres::ResidualBlockId>& blocks) {
    Eigen::Matrix3d information = Eigen::Matrix3d::Zero();
    for (const ceres::ResidualBlockId id : blocks) {
      const int m = problem.GetCostFunctionForResidualBlock(id)->num_residuals();
      Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> J(m, 3);
      std::vector<double> residuals(m);
      double* jacobians[4] = {nullptr, nullptr, nullptr, J.data()};
      double cost = 0;
      if (!problem.EvaluateResidualBlock(id, false, &cost, residuals.data(), jacobians)) continue;
      information += J.transpose() * J;
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(information);
    const double smallest = eigen.eigenvalues()(0);
    return smallest > 0 ? 1.0 / std::sqrt(smallest) : std::numeric_limits<double>::infinity();
  }

  const BaProblem& problem_;
  const MeshQuery& mesh_;
  const BaInitialState& initial_;
  BaMode mode_;
  bool model_free_;
  const BaOptions& options_;
  ServoMount mount_;
  std::unique_ptr<ceres::Manifold> pose_manifold_;
  std::unique_ptr<ceres::LossFunction> reprojection_loss_;
  std::unique_ptr<ceres::LossFunction> dvl_loss_;
  ParameterBuffer x_;  // the variables
  std::vector<uint8_t> labels_;
  ceres::Problem ceres_problem_;
};

}  // namespace

BaModeResult solve_ba_mode(const BaProblem& problem, const MeshQuery& mesh,
                           const BaInitialState& initial, BaMode mode, const BaOptions& options) {
  if (initial.T_world_vehicle.empty()) throw std::invalid_argument("ba: no keyframes");
  BaGraph graph(problem, mesh, initial, mode, options);
  return graph.solve();
}

BaInitialisation refine_initial_state(const BaProblem& problem, const MeshQuery& mesh,
                                      BaInitialState& state, const BaOptions& options) {
  BaOptions init_options = options;
  init_options.max_iterations = options.initialisation_max_iterations;
  BaGraph graph(problem, mesh, state, BaMode::kNaive, init_options, /*model_free=*/true);
  const BaModeResult r = graph.solve();
  state.T_world_vehicle = r.T_world_vehicle;
  state.servo_angle_rad = r.servo_angle_rad;
  state.T_servo_camera = r.T_servo_camera;
  for (size_t k = 0; k < r.landmarks.size(); ++k)
    state.landmarks_world[k] = r.landmarks[k].position_world;
  return {true, r.iterations, r.solve_time_s, r.initial_cost, r.final_cost};
}

std::vector<DvlBeamResidual> dvl_range_residuals(const MeshQuery& mesh, const ServoMount& mount,
                                                 const std::vector<DvlBeam>& beams,
                                                 const std::vector<int>& beam_keyframe,
                                                 const std::vector<Pose3>& T_world_vehicle,
                                                 const std::vector<double>& servo_angle_rad,
                                                 const Pose3& T_world_model, double max_range_m) {
  std::vector<DvlBeamResidual> residuals;
  for (size_t b = 0; b < beams.size(); ++b) {
    const int i = beam_keyframe[b];
    const auto hit = predict_dvl_hit(mesh, mount, beams[b], T_world_vehicle[i], servo_angle_rad[i],
                                     T_world_model, max_range_m);
    if (hit) residuals.push_back({i, hit->point_model, beams[b].range_m - hit->range_m});
  }
  return residuals;
}

}  // namespace keel::ba
