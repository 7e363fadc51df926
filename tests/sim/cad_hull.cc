#include "tests/sim/cad_hull.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "worker/io/mesh/mesh_reader.h"

namespace keel::sim {
namespace {

std::string metres(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.3g m", value);
  return buffer;
}

// The survey needs a hull longer than its lanes; a ship longer than a few kilometres is a
// file in other units.
constexpr double kMinLengthM = 2.0 * CadHullSurface::kHalfSpanM + 2.0;
constexpr double kMaxLengthM = 2000.0;

// Rays per traced section, and the sweep's last angle from straight down (rad): past the
// horizontal, the side up to the waterline.
constexpr int kSectionRays = 1500;
constexpr double kMaxSweepRad = 175.0 * M_PI / 180.0;
// Finite-difference steps of the surface normal: larger than the facets of a coarse CAD
// mesh, so lanes laid at the standoff along that normal do not kink at every facet edge.
constexpr double kNormalStepAlongM = 0.5, kNormalStepGirthM = 0.3;

}  // namespace

TriangleMesh load_cad_hull(const CadHullOptions& options) {
  if (!(std::isfinite(options.scale) && options.scale > 0.0))
    throw std::invalid_argument("--set hull.cad_scale: expected a factor > 0, got " +
                                std::to_string(options.scale));
  if (!(options.survey_x >= 0.0 && options.survey_x <= 1.0))
    throw std::invalid_argument("--set hull.cad_survey_x: expected a value in [0, 1], got " +
                                std::to_string(options.survey_x));
  TriangleMesh mesh = io::read_mesh(options.path);
  mesh.vertex_normals.clear();  // the frame changes below; the simulator uses facet normals
  mesh.vertex_colors.clear();
  for (Eigen::Vector3d& v : mesh.vertices) {
    v *= options.scale;
    if (options.z_down) v = Eigen::Vector3d(v.x(), -v.y(), -v.z());  // 180 deg about x
  }
  Eigen::AlignedBox3d box;
  for (const Eigen::Vector3d& v : mesh.vertices) box.extend(v);
  const Eigen::Vector3d size = box.sizes();
  if (size.x() < kMinLengthM || size.x() > kMaxLengthM)
    throw std::invalid_argument(
        "hull.cad: " + options.path + " is " + metres(size.x()) + " long along x after " +
        "hull.cad_scale " + std::to_string(options.scale) + "; the survey needs a hull from " +
        metres(kMinLengthM) + " to " + metres(kMaxLengthM) +
        " long along x (a file in millimetres needs --set hull.cad_scale=0.001)");
  if (size.x() < std::max(size.y(), size.z()))
    throw std::invalid_argument("hull.cad: " + options.path + " is " + metres(size.x()) +
                                " along x but " + metres(size.y()) + " along y and " +
                                metres(size.z()) + " along z; x must run along the hull");
  const double draft = options.draft_m > 0.0 ? options.draft_m : 0.5 * size.z();
  if (!(std::isfinite(draft) && draft < size.z()))
    throw std::invalid_argument("--set hull.cad_draft: " + metres(draft) +
                                " is not below the hull's depth, " + metres(size.z()));
  const double waterline_z = box.min().z() + draft;
  for (Eigen::Vector3d& v : mesh.vertices) v.z() -= waterline_z;
  return mesh;
}

CadHullSurface::CadHullSurface(const TriangleMesh& mesh, double survey_x) : bvh_(mesh) {
  Eigen::AlignedBox3d box;
  for (const Eigen::Vector3d& v : mesh.vertices) box.extend(v);
  x_center_ = box.min().x() + survey_x * box.sizes().x();
  z_axis_ = 0.5 * box.min().z();  // half the draft: the keel is the lowest point
  reach_m_ = 2.0 * box.sizes().norm() + 1.0;
  // The lowest lane clear of the turn of the bilge: the DVL's 30-degree beams reach 0.87 m
  // either side of a lane at 1.5 m standoff and lane changes overshoot by up to 0.4 m, so on
  // a square bilge (KCS's mid-body) the lower beams would pass under the hull.
  girth_middle_m_ = bilge_girth(x_center_) + kBilgeClearanceM +
                    (kMiddleLaneSigma - kLowestLaneSigma) * kGirthPerSigmaM;
  // The band of lanes and of the objects around them (hauv-hull: sigma 0.30-0.88) must lie
  // between the keel and the waterline over the survey's length.
  const double below = girth_middle_m_ - (kMiddleLaneSigma - 0.25) * kGirthPerSigmaM;
  survey_center_ = point(x_center_, girth_middle_m_);
  const double above = girth_middle_m_ + (0.93 - kMiddleLaneSigma) * kGirthPerSigmaM;
  for (const double dx : {-kHalfSpanM - 1.0, 0.0, kHalfSpanM + 1.0}) {
    const double girth = half_girth_m(x_center_ + dx);
    if (below < 0.0 || above > girth)
      throw std::invalid_argument(
          "hull.cad: the survey band (" + metres(below) + " to " + metres(above) +
          " of girth from the keel, on the side above the turn of the bilge) does not fit on the "
          "wetted "
          "starboard side at x = " +
          metres(x_center_ + dx) + " (" + metres(girth) +
          " from the keel to the waterline); check hull.cad_draft, hull.cad_z_down and "
          "hull.cad_survey_x");
  }
}

const CadHullSurface::Section& CadHullSurface::section(double x) const {
  if (const auto it = sections_.find(x); it != sections_.end()) return it->second;
  // Rays in the plane of the section, from far outside towards the axis point, swept from
  // straight below the keel round the starboard side: the first hit of each is the outer
  // skin, whatever the mesh holds inside (decks, bulkheads) or whether it is closed.
  const Eigen::Vector3d axis(x, 0.0, z_axis_);
  Section s;
  for (int i = 0; i <= kSectionRays; ++i) {
    const double phi = kMaxSweepRad * i / kSectionRays;
    const Eigen::Vector3d out(0.0, -std::sin(phi), -std::cos(phi));  // starboard is -y
    MeshHit hit;
    if (!bvh_.raycast(axis + reach_m_ * out, -out, 0.0, reach_m_, &hit)) {
      if (i == 0)
        throw std::invalid_argument("hull.cad: no hull below the centreline at x = " + metres(x) +
                                    " (the survey runs " + metres(kHalfSpanM) +
                                    " either side of hull.cad_survey_x)");
      continue;  // a gap in an open mesh
    }
    const Eigen::Vector3d p = axis + (reach_m_ - hit.t) * out;
    Eigen::Vector2d yz(p.y(), p.z());
    const bool wet = yz.y() < 0.0;
    if (!wet && !s.yz.empty()) {  // cut at the waterline
      const Eigen::Vector2d& last = s.yz.back();
      yz = last + (yz - last) * (-last.y() / (yz.y() - last.y()));
    }
    s.girth.push_back(s.yz.empty() ? 0.0 : s.girth.back() + (yz - s.yz.back()).norm());
    s.yz.push_back(yz);
    if (!wet) break;
  }
  return sections_.emplace(x, std::move(s)).first->second;
}

Eigen::Vector3d CadHullSurface::point(double x, double girth_m) const {
  const Section& s = section(x);
  if (s.yz.size() < 2) return {x, s.yz.front().x(), s.yz.front().y()};
  const double g = std::clamp(girth_m, 0.0, s.girth.back());
  size_t i = std::upper_bound(s.girth.begin(), s.girth.end(), g) - s.girth.begin();
  i = std::clamp<size_t>(i, 1, s.girth.size() - 1) - 1;
  const double w = (g - s.girth[i]) / std::max(s.girth[i + 1] - s.girth[i], 1e-12);
  const Eigen::Vector2d yz = (1.0 - w) * s.yz[i] + w * s.yz[i + 1];
  return {x, yz.x(), yz.y()};
}

double CadHullSurface::bilge_girth(double x) const {
  // The first girth at which the section faces more sideways than downwards.
  const double total = section(x).girth.back();
  for (double g = kNormalStepGirthM; g < total - kNormalStepGirthM; g += 0.05) {
    const Eigen::Vector3d tangent =
        point(x, g + kNormalStepGirthM) - point(x, g - kNormalStepGirthM);  // keel to waterline
    // Outward normal of the starboard section: the tangent turned by -90 degrees in (y, z).
    const Eigen::Vector2d normal(tangent.z(), -tangent.y());
    if (std::abs(normal.x()) >= std::abs(normal.y())) return g;
  }
  throw std::invalid_argument("hull.cad: the section at x = " + metres(x) +
                              " never turns from the bottom to the side below the waterline; "
                              "check hull.cad_draft and hull.cad_z_down");
}

SurfacePoint CadHullSurface::surface(double x_m, double sigma) const {
  const double x = x_center_ + x_m;
  const double girth = girth_middle_m_ + (sigma - kMiddleLaneSigma) * kGirthPerSigmaM;
  SurfacePoint out;
  out.p = point(x, girth);
  const Eigen::Vector3d d_x =
      point(x + kNormalStepAlongM, girth) - point(x - kNormalStepAlongM, girth);
  const Eigen::Vector3d d_girth =
      point(x, girth + kNormalStepGirthM) - point(x, girth - kNormalStepGirthM);
  out.normal = d_x.cross(d_girth).normalized();
  const Eigen::Vector3d axis(x, 0.0, z_axis_);
  if (out.normal.dot(out.p - axis) < 0.0) out.normal = -out.normal;
  return out;
}

}  // namespace keel::sim
