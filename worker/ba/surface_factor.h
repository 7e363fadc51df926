// Surface constraint of Sec. 2.3-2.4, seed 001 (Eq. 4-7).
//
// h(x_gM, l_i) (Eq. 5) is the orthogonal signed distance of landmark l_i, taken into the model
// frame by H_g^M = x_gM^-1, to the closest triangle of M_prior. The paper finds that triangle
// through the closest vertex (KD tree); we take the exact closest point p on the mesh (AABB
// tree, mesh_query.h) and write h = (H l - p)^T u with u the unit direction from p to the
// landmark, signed by the pseudonormal test. Inside a face u is the face normal n, exactly
// Eq. (5); at an edge or a vertex u is the gradient of the distance there, so h is the
// true signed distance everywhere and its derivative (p, u held at the current closest
// point) is exact: d h / d l_M = u.
//
// Cost (issue 6: `proposed` <= +25 % of `naive`): the factor is a SizedCostFunction with the
// Jacobian in closed form (d h / d l_world = R u, d h / d t = -R u, d h / d q through the
// quaternion, see surface_factor.cc), and each factor keeps a LocalClosestPoint (mesh_query.h):
// the landmark moves millimetres per iteration, so the exact closest point comes from brute
// force over the few faces near the last tree query instead of an AABB-tree query per
// evaluation. Both were measured (tests/bench/mesh_query_bench.cc, tests/bench/ba_bench.cc).
//
// Eq. (4): z_s_i | lambda_i ~ N(h, sigma_lambda^2), with z_s_i = surface_offset (0 here).
// Eq. (7): p(z_s | X) = eta max_lambda p(z_s | lambda, X), equal weights. Its negative log,
// up to a constant, is
//   -log p = min_lambda [ e^2 / (2 sigma_lambda^2) + log sigma_lambda ],  e = z_s - h.
// Normalisation constants: dropping the log sigma_lambda terms (treating both components as
// unnormalised least squares) would always pick the wide component sigma_0. We keep them, as
// Olson & Agarwal [47] do, and make them least-squares friendly by subtracting
// log sigma_min (a constant, so the argmax and the optimum are unchanged), which makes every
// term non-negative. The factor then has two residuals,
//   r = [ e / sigma_lambda ;  sqrt(2 log(sigma_lambda / sigma_min)) ],
// with 0.5 |r|^2 = -log p + const. The second residual is constant for a given lambda: the
// Gauss-Newton Hessian of the chosen component is exactly 1 / sigma_lambda^2 (a single
// residual sqrt(e^2/sigma^2 + c) would understate it). 0.5 |r|^2 is continuous where lambda
// switches because both components have the same value there: that is how the switch point
//   |e*| = sqrt(2 log(sigma_0 / sigma_1) / (1 / sigma_1^2 - 1 / sigma_0^2))
// is defined (5.6 cm for the defaults; Fig. 7 of the paper says "about 5 cm").
#pragma once

#include <ceres/cost_function.h>

#include <Eigen/Core>

#include <cstdint>

#include "core/mesh_query.h"
#include "core/pose.h"

namespace keel::ba {

struct MaxMixture {
  double sigma0_m = 1.0;   // lambda = 0: structure absent from the model
  double sigma1_m = 0.02;  // lambda = 1: on the nominal surface

  // Eq. (7): argmax_lambda p(z_s | lambda, X) for the error e = z_s - h. Ties go to 1.
  int label(double error_m) const;
  double sigma(int lambda) const { return lambda == 1 ? sigma1_m : sigma0_m; }
  // sqrt(2 log(sigma_lambda / sigma_min)): the normalisation residual.
  double normalisation_residual(int lambda) const;
  // 0.5 |r|^2 of the chosen component: -log of Eq. (7) up to a constant.
  double cost(double error_m) const;
  double switching_distance_m() const;
};

enum class SurfaceMode {
  kMaxMixture,  // `proposed`: lambda from Eq. (7) at every evaluation
  kOnModel,     // `geva`: lambda = 1 always
};

// Parameters: x_gM (7), landmark l_i (3). Two residuals (see above; for kOnModel the second
// is 0). When `label_slot` is not null, every evaluation with Jacobians writes the label
// Eq. (7) picks there: Ceres evaluates Jacobians only at accepted states, so after an
// iteration the slots hold the current labels (Fig. 16) at no extra mesh query.
// `mesh` must outlive the cost function. Each cost function caches its landmark's nearby
// faces (`cache`, see above): give every residual block its own cost function. Concurrent
// evaluations of one cost function stay correct (the loser of a try-lock asks the tree).
ceres::CostFunction* make_surface_factor(const MeshQuery& mesh, const MaxMixture& mixture,
                                         SurfaceMode mode, double surface_offset_m,
                                         uint8_t* label_slot = nullptr,
                                         const LocalClosestPointOptions& cache = {});

// h(x_gM, l) of Eq. (5) for a landmark in the world frame.
double signed_distance_to_model(const MeshQuery& mesh, const Pose3& T_world_model,
                                const Eigen::Vector3d& landmark_world);

}  // namespace keel::ba
