// A user's CAD hull for keel-sim's hauv-hull (`--set hull.cad=FILE`): the mesh, read with
// Keel's own readers (PLY, OBJ, STL, OFF), scaled and turned into keel-sim's CAD frame, and
// its wetted starboard side as a HullSurface, traced section by section with ray casts, so
// that long hulls with flat mid-bodies, bulbous bows and open or non-manifold meshes survey
// like the procedural one.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "tests/sim/hull_surface.h"
#include "tests/sim/mesh_bvh.h"

namespace keel::sim {

struct CadHullOptions {
  std::string path;     // hull.cad; empty: the procedural hull
  double scale = 1.0;   // hull.cad_scale: file units to metres (0.001 for millimetres)
  bool z_down = false;  // hull.cad_z_down: the file's z points down (ship axes x forward,
                        // y starboard, z down); turned 180 deg about x
  // hull.cad_draft: the waterline's height above the hull's lowest point, m; 0: half the
  // hull's depth.
  double draft_m = 0.0;
  // hull.cad_survey_x: the survey's centre along the hull, 0 = aft end, 1 = forward end.
  double survey_x = 0.5;
};

// The hull in keel-sim's CAD frame (hull_model.h): the file's x along the hull, z up,
// the waterline at z = 0. Throws io::MeshReadError for an unreadable file (naming it) and
// std::invalid_argument naming the setting for bad options or a hull whose size says the
// units are wrong.
TriangleMesh load_cad_hull(const CadHullOptions& options);

// sigma on a CAD hull: girth from the keel's centreline around the starboard section, in
// units of the procedural hull's half-girth (8.24 m), so the lanes lie 1.07 m apart as there,
// and shifted so that the lowest lane (sigma 0.33) runs kBilgeClearanceM above the turn of the
// bilge at the survey's centre (where the section's outward normal is 45 degrees below the
// horizontal): the survey covers the side above the bilge.
class CadHullSurface : public HullSurface {
 public:
  static constexpr double kGirthPerSigmaM = 8.24;
  static constexpr double kMiddleLaneSigma = 0.59, kLowestLaneSigma = 0.33;
  static constexpr double kBilgeClearanceM = 1.5;
  static constexpr double kHalfSpanM = 5.0;  // the survey's half length along the hull

  // `mesh` in the CAD frame (load_cad_hull). Throws std::invalid_argument when the surveyed
  // band does not fit on the hull there.
  CadHullSurface(const TriangleMesh& mesh, double survey_x);
  SurfacePoint surface(double x_m, double sigma) const override;
  // The middle lane's hull point at the survey's centre.
  Eigen::Vector3d survey_center() const override { return survey_center_; }

  // Girth of the starboard half-section at CAD x, keel to waterline, m.
  double half_girth_m(double x) const { return section(x).girth.back(); }
  // Girth of the middle lane (sigma 0.59), m.
  double middle_girth_m() const { return girth_middle_m_; }

 private:
  struct Section {
    std::vector<Eigen::Vector2d> yz;  // traced points, keel to waterline
    std::vector<double> girth;        // arc length at each, m
  };
  const Section& section(double x) const;
  Eigen::Vector3d point(double x, double girth_m) const;
  double bilge_girth(double x) const;

  MeshBvh bvh_;
  double x_center_ = 0.0;
  double z_axis_ = 0.0;   // the sections are traced towards (x, 0, z_axis_)
  double reach_m_ = 0.0;  // rays start this far from that axis
  double girth_middle_m_ = 0.0;
  Eigen::Vector3d survey_center_ = Eigen::Vector3d::Zero();
  mutable std::map<double, Section> sections_;
};

}  // namespace keel::sim
