// DVL raycast factor of Sec. 2.6.5, seed 001 (Eq. 14): the range of beam n predicted by
// casting it from the DVL (on the servoed tray) into the prior mesh placed at x_gM,
//   r = (z_r_in - h_rn(x_gM, x_gv_i, theta_v_i_s_i; M_prior)) / sigma,   sigma = 3 mm.
// The paper casts with an octree; we use the AABB tree of mesh_query.h. Parameters: vehicle
// pose x_gv_i (7), servo angle (1), model pose x_gM (7).
//
// Derivative: the cast picks the hit triangle at the current value; on that triangle the
// range is the ray-plane intersection t = n.(p - o) / n.d, whose derivative w.r.t. the ray
// origin o and direction d is exact (auto-diff). It changes only where the ray crosses an
// edge, where the range itself is continuous for a closed surface.
// A beam that stops hitting the mesh during the optimisation contributes a constant residual
// of gate / sigma (zero gradient): as much as the worst beam admitted, so leaving the mesh is
// never a way to lower the cost.
#pragma once

#include <ceres/cost_function.h>

#include <Eigen/Core>

#include <optional>

#include "worker/ba/mesh_query.h"
#include "worker/ba/rig_geometry.h"

namespace keel::ba {

struct DvlBeam {
  Eigen::Vector3d origin_servo = Eigen::Vector3d::Zero();      // T_servo_dvl translation
  Eigen::Vector3d direction_servo = Eigen::Vector3d::UnitZ();  // unit
  double range_m = 0;                                          // measured
};

// Beam in the servo frame from its direction in the DVL frame.
DvlBeam make_dvl_beam(const Pose3& T_servo_dvl, const Eigen::Vector3d& direction_dvl,
                      double range_m);

// `mesh` must outlive the cost function.
ceres::CostFunction* make_dvl_raycast_factor(const MeshQuery& mesh, const ServoMount& mount,
                                             const DvlBeam& beam, double sigma_m,
                                             double max_range_m, double gate_m);

// h_rn of Eq. (14) at given values: the predicted range, nullopt when the beam misses.
std::optional<double> predict_dvl_range(const MeshQuery& mesh, const ServoMount& mount,
                                        const DvlBeam& beam, const Pose3& T_world_vehicle,
                                        double servo_angle_rad, const Pose3& T_world_model,
                                        double max_range_m);

}  // namespace keel::ba
