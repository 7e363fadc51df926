#include "worker/ba/surface_factor.h"

#include <ceres/sized_cost_function.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <atomic>
#include <cmath>

#include "worker/ba/pose_block.h"

namespace keel::ba {
namespace {

// Below this distance the direction p -> l is numerically meaningless; use the normal.
constexpr double kOnSurfaceM = 1e-9;

// Eq. (5) at the closest point: h = (l_M - p)^T u with u the unit direction from p to l_M,
// signed (see the header). u is also d h / d l_M.
struct SignedDistance {
  double h_m;
  Eigen::Vector3d u;
};

SignedDistance signed_distance_at(const ClosestPoint& closest, const Eigen::Vector3d& l_model) {
  Eigen::Vector3d u = closest.normal;
  if (closest.distance_m > kOnSurfaceM) {
    const double sign = closest.signed_distance_m < 0 ? -1.0 : 1.0;
    u = sign * (l_model - closest.point) / closest.distance_m;
  }
  return {(l_model - closest.point).dot(u), u};
}

// d h / d q for l_M = R(q / |q|)^T (l_world - t) and h = u^T l_M + const, q in the block's
// storage order [x y z w]. For a unit q = (w, e), R^T v = v - 2 w (e x v) + 2 e x (e x v), so
//   d h / d w = -2 u . (e x v),
//   d h / d e = 2 w (u x v) + 2 ((u . e) v + (e . v) u - 2 (u . v) e);
// the normalisation q / |q| projects that onto the sphere's tangent space and divides by |q|.
Eigen::Vector4d dh_dquaternion(const Eigen::Vector4d& q_xyzw, const Eigen::Vector3d& v,
                               const Eigen::Vector3d& u) {
  const double norm = q_xyzw.norm();
  const Eigen::Vector4d q = q_xyzw / norm;
  const Eigen::Vector3d e = q.head<3>();
  const double w = q[3];
  Eigen::Vector4d g;
  g.head<3>() = 2.0 * w * u.cross(v) + 2.0 * (u.dot(e) * v + e.dot(v) * u - 2.0 * u.dot(v) * e);
  g[3] = -2.0 * u.dot(e.cross(v));
  return (g - q * q.dot(g)) / norm;
}

// Eq. (4)-(7) with the closed-form Jacobian; parameters x_gM (7) and l_i in the world (3).
class SurfaceFactor : public ceres::SizedCostFunction<2, kPoseBlockSize, 3> {
 public:
  SurfaceFactor(const MeshQuery& mesh, const MaxMixture& mixture, SurfaceMode mode, double offset_m,
                uint8_t* label_slot, const LocalClosestPointOptions& cache)
      : mesh_(mesh),
        mixture_(mixture),
        mode_(mode),
        offset_m_(offset_m),
        label_slot_(label_slot),
        normalisation_{mixture.normalisation_residual(0), mixture.normalisation_residual(1)},
        cache_(mesh, cache) {}

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const double* model = parameters[0];
    const Eigen::Vector4d q_xyzw(model[0], model[1], model[2], model[3]);
    if (!(q_xyzw.squaredNorm() > 0)) return false;  // no rotation (NaN or zero quaternion)
    const Eigen::Matrix3d R_world_model = block_rotation(model).normalized().toRotationMatrix();
    const Eigen::Vector3d v = Eigen::Map<const Eigen::Vector3d>(parameters[1]) -
                              Eigen::Map<const Eigen::Vector3d>(model + 4);
    const Eigen::Vector3d l_model = R_world_model.transpose() * v;  // H_g^M l_i
    if (!l_model.allFinite()) return false;
    const SignedDistance d = signed_distance_at(closest_point(l_model), l_model);
    const double error = offset_m_ - d.h_m;   // z_s - h
    const int label = mixture_.label(error);  // Eq. (7)
    if (jacobians != nullptr && label_slot_ != nullptr) *label_slot_ = static_cast<uint8_t>(label);
    const int used = mode_ == SurfaceMode::kOnModel ? 1 : label;
    const double inv_sigma = 1.0 / mixture_.sigma(used);
    residuals[0] = error * inv_sigma;     // Eq. (4)
    residuals[1] = normalisation_[used];  // log-normaliser of Eq. (7)
    if (jacobians == nullptr) return true;
    // r0 = (z_s - h) / sigma: d r0 = -d h / sigma; r1 is constant for a given lambda.
    const Eigen::Vector3d dh_dl_world = R_world_model * d.u;
    if (jacobians[0] != nullptr) {
      Eigen::Map<Eigen::Matrix<double, 2, kPoseBlockSize, Eigen::RowMajor>> J(jacobians[0]);
      J.row(1).setZero();
      J.block<1, 4>(0, 0) = -inv_sigma * dh_dquaternion(q_xyzw, v, d.u).transpose();
      J.block<1, 3>(0, 4) = inv_sigma * dh_dl_world.transpose();  // d h / d t = -R u
    }
    if (jacobians[1] != nullptr) {
      Eigen::Map<Eigen::Matrix<double, 2, 3, Eigen::RowMajor>> J(jacobians[1]);
      J.row(0) = -inv_sigma * dh_dl_world.transpose();
      J.row(1).setZero();
    }
    return true;
  }

 private:
  // Ceres evaluates each residual block from one thread at a time, so the try-lock always
  // wins there; it only guards a cost function shared by several blocks or callers.
  ClosestPoint closest_point(const Eigen::Vector3d& l_model) const {
    if (busy_.test_and_set(std::memory_order_acquire)) return mesh_.closest_point(l_model);
    struct Release {
      std::atomic_flag& flag;
      ~Release() { flag.clear(std::memory_order_release); }
    } release{busy_};
    return cache_.closest_point(l_model);
  }

  const MeshQuery& mesh_;
  MaxMixture mixture_;
  SurfaceMode mode_;
  double offset_m_;
  uint8_t* label_slot_;
  double normalisation_[2];
  // The cache changes nothing observable (LocalClosestPoint is exact), hence mutable.
  mutable LocalClosestPoint cache_;
  mutable std::atomic_flag busy_ = ATOMIC_FLAG_INIT;
};

}  // namespace

int MaxMixture::label(double error_m) const {
  // Compare -2 log p_lambda = e^2 / sigma^2 + 2 log sigma (+ shared constant).
  const double e2 = error_m * error_m;
  const double on = e2 / (sigma1_m * sigma1_m) + 2.0 * std::log(sigma1_m);
  const double off = e2 / (sigma0_m * sigma0_m) + 2.0 * std::log(sigma0_m);
  return on <= off ? 1 : 0;
}

double MaxMixture::normalisation_residual(int lambda) const {
  const double sigma_min = std::min(sigma0_m, sigma1_m);
  return std::sqrt(2.0 * std::log(sigma(lambda) / sigma_min));
}

double MaxMixture::cost(double error_m) const {
  const int lambda = label(error_m);
  const double r0 = error_m / sigma(lambda);
  const double r1 = normalisation_residual(lambda);
  return 0.5 * (r0 * r0 + r1 * r1);
}

double MaxMixture::switching_distance_m() const {
  const double s0 = sigma0_m * sigma0_m, s1 = sigma1_m * sigma1_m;
  return std::sqrt(2.0 * std::log(sigma0_m / sigma1_m) / (1.0 / s1 - 1.0 / s0));
}

ceres::CostFunction* make_surface_factor(const MeshQuery& mesh, const MaxMixture& mixture,
                                         SurfaceMode mode, double surface_offset_m,
                                         uint8_t* label_slot,
                                         const LocalClosestPointOptions& cache) {
  return new SurfaceFactor(mesh, mixture, mode, surface_offset_m, label_slot, cache);
}

double signed_distance_to_model(const MeshQuery& mesh, const Pose3& T_world_model,
                                const Eigen::Vector3d& landmark_world) {
  const Eigen::Vector3d l_model = T_world_model.inverse() * landmark_world;
  return signed_distance_at(mesh.closest_point(l_model), l_model).h_m;
}

}  // namespace keel::ba
