// DVL raycast factor of Sec. 2.6.5, seed 001 (Eq. 14): the range of beam n predicted by
// casting it from the DVL (on the servoed tray) into the prior mesh placed at x_gM,
//   r = (z_r_in - h_rn(x_gM, x_gv_i, theta_v_i_s_i; M_prior)) / sigma,   sigma = 3 mm.
// The paper casts with an octree; we use the AABB tree of mesh_query.h. Parameters: vehicle
// pose x_gv_i (7), servo angle (1), model pose x_gM (7).
//
// Derivative: the cast picks the hit point p at the current value; the range is linearised as
// the intersection with the plane through p of normal n, t = n.(p - o) / n.d, auto-diffed
// w.r.t. the ray origin o and direction d. Its value is the exact facet range for any n. The
// paper leaves n open; we take the smooth surface's normal (RayHit::interpolated_normal) by
// default, not the hit facet's. Why: the CAD facets tessellate a smooth hull, and a facet's
// normal jumps at every edge. On keel-sim hauv-hull, Levenberg-Marquardt steps move most beams
// across an edge (x_gM slides along the hull), and the facet linearisation then mispredicts
// the cost change: measured per step, the beams that changed face carried nearly all of the
// gap between predicted and actual decrease. Over the 9 full-survey solves of 3 seeds
// (bench_hull_sim 3 0), facet normals took 121 iterations with 28 rejected steps (up to 24
// iterations in one solve), smooth normals 84 with none (8-10 per solve), at the same DVL
// residuals and shapes. kFacet gives the exact derivative of the facet range (which is the
// default's too on flat faces and up to sharp creases).
// A beam that stops hitting the mesh during the optimisation contributes a constant residual
// of gate / sigma (zero gradient): as much as the worst beam admitted, so leaving the mesh is
// never a way to lower the cost.
#pragma once

#include <ceres/cost_function.h>

#include <Eigen/Core>

#include <optional>

#include "worker/ba/ba_options.h"
#include "core/mesh_query.h"
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
                                             double max_range_m, double gate_m,
                                             DvlRangeNormal normal = DvlRangeNormal::kInterpolated);

// Where a beam meets the prior mesh at given values: h_rn of Eq. (14) and the hit point.
struct DvlHit {
  double range_m = 0;
  Eigen::Vector3d point_model = Eigen::Vector3d::Zero();  // on M_prior, model frame
};
// nullopt when the beam misses within max_range_m.
std::optional<DvlHit> predict_dvl_hit(const MeshQuery& mesh, const ServoMount& mount,
                                      const DvlBeam& beam, const Pose3& T_world_vehicle,
                                      double servo_angle_rad, const Pose3& T_world_model,
                                      double max_range_m);

// h_rn of Eq. (14) at given values: the predicted range, nullopt when the beam misses.
std::optional<double> predict_dvl_range(const MeshQuery& mesh, const ServoMount& mount,
                                        const DvlBeam& beam, const Pose3& T_world_vehicle,
                                        double servo_angle_rad, const Pose3& T_world_model,
                                        double max_range_m);

}  // namespace keel::ba
