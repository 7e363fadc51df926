#include "tests/sim/hull_model.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "tests/sim/rng.h"

namespace keel::sim {

HullShape::HullShape(const HullOptions& options) : options_(options) {
  if (options.length_m <= 0 || options.beam_m <= 0 || options.draft_m <= 0 ||
      options.section_exponent < 2.0)
    throw std::invalid_argument("HullOptions: sizes must be > 0 and section_exponent >= 2");
  // Dense table of the midship section's arc length against the superellipse angle phi.
  const int n = 8000;
  double cumulative = 0.0;
  Eigen::Vector2d previous;
  for (int i = 0; i <= n; ++i) {
    const double phi = -0.5 * M_PI + M_PI * i / n;
    const double e = 2.0 / options.section_exponent;
    const Eigen::Vector2d q(
        -0.5 * options.beam_m * std::copysign(std::pow(std::abs(std::sin(phi)), e), std::sin(phi)),
        -options.draft_m * std::pow(std::abs(std::cos(phi)), e));
    if (i > 0) cumulative += (q - previous).norm();
    previous = q;
    table_phi_.push_back(phi);
    arc_.push_back(cumulative);
  }
  for (double& a : arc_) a = 2.0 * a / cumulative - 1.0;
}

double HullShape::taper(double xi) const {
  // Fine bow, fuller stern: both reach zero beyond |xi| = 1, where the mesh is capped anyway.
  const double a = std::min(std::abs(xi), 1.0);
  return xi >= 0.0 ? std::sqrt(1.0 - a * a * a) : std::pow(1.0 - std::pow(a, 5.0), 0.3);
}

Eigen::Vector3d HullShape::point(double xi, double sigma) const {
  sigma = std::clamp(sigma, -1.0, 1.0);
  size_t i = std::upper_bound(arc_.begin(), arc_.end(), sigma) - arc_.begin();
  i = std::clamp<size_t>(i, 1, arc_.size() - 1) - 1;
  const double w = (sigma - arc_[i]) / std::max(arc_[i + 1] - arc_[i], 1e-15);
  const double phi = table_phi_[i] + w * (table_phi_[i + 1] - table_phi_[i]);
  const double e = 2.0 / options_.section_exponent;
  const double s = std::sin(phi);
  return {0.5 * xi * options_.length_m,
          -0.5 * options_.beam_m * taper(xi) * std::copysign(std::pow(std::abs(s), e), s),
          -options_.draft_m * std::pow(std::abs(std::cos(phi)), e)};
}

SurfacePoint HullShape::surface(double xi, double sigma) const {
  const double h = 1e-5;
  const double s0 = std::max(sigma - h, -1.0), s1 = std::min(sigma + h, 1.0);
  const Eigen::Vector3d d_xi = point(xi + h, sigma) - point(xi - h, sigma);
  const Eigen::Vector3d d_sigma = point(xi, s1) - point(xi, s0);
  SurfacePoint out;
  out.p = point(xi, sigma);
  out.normal = d_xi.cross(d_sigma).normalized();
  const Eigen::Vector3d center(out.p.x(), 0.0, -0.5 * options_.draft_m);
  if (out.normal.dot(out.p - center) < 0.0) out.normal = -out.normal;
  return out;
}

TriangleMesh make_hull_mesh(const HullOptions& options) {
  const HullShape shape(options);
  const int n_len = options.length_segments, n_sec = options.section_segments,
            n_fb = options.freeboard_segments;
  if (n_len < 2 || n_sec < 4 || n_fb < 1)
    throw std::invalid_argument("HullOptions: too few segments");
  const int rows = n_fb + n_sec + 1 + n_fb;  // port topside, section, starboard topside
  TriangleMesh mesh;
  for (int i = 0; i <= n_len; ++i) {
    const double xi = -options.end_xi + 2.0 * options.end_xi * i / n_len;
    const Eigen::Vector3d port = shape.surface(xi, -1.0).p, starboard = shape.surface(xi, 1.0).p;
    for (int k = 0; k < n_fb; ++k)
      mesh.vertices.emplace_back(port.x(), port.y(),
                                 options.freeboard_m * (1.0 - double(k) / n_fb));
    for (int j = 0; j <= n_sec; ++j)
      mesh.vertices.push_back(shape.surface(xi, -1.0 + 2.0 * j / n_sec).p);
    for (int k = 1; k <= n_fb; ++k)
      mesh.vertices.emplace_back(starboard.x(), starboard.y(),
                                 options.freeboard_m * double(k) / n_fb);
  }
  auto v = [rows](int i, int r) { return i * rows + r; };
  // Shell: (i, r) -> (i+1, r) -> (i+1, r+1) faces outward (x cross the around-section direction).
  for (int i = 0; i < n_len; ++i) {
    for (int r = 0; r + 1 < rows; ++r) {
      mesh.faces.emplace_back(v(i, r), v(i + 1, r), v(i + 1, r + 1));
      mesh.faces.emplace_back(v(i, r), v(i + 1, r + 1), v(i, r + 1));
    }
    // Deck between the port (r = 0) and starboard (r = rows - 1) top edges, normal +z.
    mesh.faces.emplace_back(v(i, 0), v(i, rows - 1), v(i + 1, rows - 1));
    mesh.faces.emplace_back(v(i, 0), v(i + 1, rows - 1), v(i + 1, 0));
  }
  // Caps (convex sections): fans from the section centroid; stern faces -x, bow +x.
  for (int end = 0; end < 2; ++end) {
    const int i = end == 0 ? 0 : n_len;
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (int r = 0; r < rows; ++r) centroid += mesh.vertices[v(i, r)];
    const int c = static_cast<int>(mesh.vertices.size());
    mesh.vertices.push_back(centroid / rows);
    for (int r = 0; r < rows; ++r) {
      const int a = v(i, r), b = v(i, (r + 1) % rows);
      if (end == 0)
        mesh.faces.emplace_back(c, a, b);
      else
        mesh.faces.emplace_back(c, b, a);
    }
  }
  return mesh;
}

namespace {
void basis(const Eigen::Vector3d& axis, Eigen::Vector3d* u, Eigen::Vector3d* w) {
  const Eigen::Vector3d helper =
      std::abs(axis.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  *u = axis.cross(helper).normalized();
  *w = axis.cross(*u);
}
}  // namespace

TriangleMesh foreign_object_mesh(const ForeignObject& object) {
  constexpr int kSegments = 32;
  constexpr double kSink = 0.01;  // base below the hull surface
  const Eigen::Vector3d a = object.axis.normalized();
  Eigen::Vector3d u, w;
  basis(a, &u, &w);
  auto at = [&](double rho, double angle, double height) {
    return Eigen::Vector3d(object.center + rho * (std::cos(angle) * u + std::sin(angle) * w) +
                           height * a);
  };
  TriangleMesh mesh;
  std::vector<double> ring_rho, ring_height;
  if (object.kind == ForeignObject::Kind::kCylinder) {
    ring_rho = {object.radius_m, object.radius_m};
    ring_height = {-kSink, object.height_m};
  } else {
    // Biofouling bump: raised-cosine profile h(rho) = H (1 + cos(pi rho / R)) / 2.
    constexpr int kRings = 6;
    for (int j = 0; j < kRings; ++j) {
      const double rho = object.radius_m * (1.0 - double(j) / kRings);
      ring_rho.push_back(rho);
      ring_height.push_back(
          j == 0 ? -kSink : 0.5 * object.height_m * (1.0 + std::cos(M_PI * rho / object.radius_m)));
    }
  }
  for (size_t j = 0; j < ring_rho.size(); ++j)
    for (int k = 0; k < kSegments; ++k)
      mesh.vertices.push_back(at(ring_rho[j], 2.0 * M_PI * k / kSegments, ring_height[j]));
  const int apex = static_cast<int>(mesh.vertices.size());
  mesh.vertices.push_back(object.center + object.height_m * a);
  auto idx = [](size_t j, int k) { return static_cast<int>(j * kSegments + (k % kSegments)); };
  for (size_t j = 0; j + 1 < ring_rho.size(); ++j) {
    for (int k = 0; k < kSegments; ++k) {
      mesh.faces.emplace_back(idx(j, k), idx(j, k + 1), idx(j + 1, k + 1));
      mesh.faces.emplace_back(idx(j, k), idx(j + 1, k + 1), idx(j + 1, k));
    }
  }
  const size_t top = ring_rho.size() - 1;
  for (int k = 0; k < kSegments; ++k) mesh.faces.emplace_back(apex, idx(top, k), idx(top, k + 1));
  return mesh;
}

std::vector<Landmark> scatter_landmarks(const TriangleMesh& mesh, double density_per_m2,
                                        double max_normal_z, bool on_cad, int64_t first_id,
                                        uint64_t seed, uint64_t stream_index,
                                        const std::function<bool(const Eigen::Vector3d&)>& keep) {
  Rng rng(seed, Stream::kLandmarks, stream_index);
  std::vector<Landmark> out;
  int64_t id = first_id;
  for (const auto& f : mesh.faces) {
    const Eigen::Vector3d &a = mesh.vertices[f[0]], &b = mesh.vertices[f[1]],
                          &c = mesh.vertices[f[2]];
    const Eigen::Vector3d cross = (b - a).cross(c - a);
    const double area = 0.5 * cross.norm();
    if (area <= 0.0) continue;
    const Eigen::Vector3d normal = cross.normalized();
    if (normal.z() > max_normal_z) continue;
    const int count = static_cast<int>(std::floor(area * density_per_m2 + rng.uniform()));
    for (int k = 0; k < count; ++k) {
      const double r1 = std::sqrt(rng.uniform()), r2 = rng.uniform();
      const Eigen::Vector3d p = (1.0 - r1) * a + r1 * (1.0 - r2) * b + r1 * r2 * c;
      if (keep && !keep(p)) continue;
      Landmark lm;
      lm.id = id++;
      lm.p_world = p;
      lm.normal_world = normal;
      lm.radius_m = rng.uniform(0.015, 0.04);
      lm.albedo = rng.uniform() < 0.5 ? 0.08 : 0.92;
      lm.on_cad = on_cad;
      out.push_back(lm);
    }
  }
  return out;
}

TriangleMesh transform_mesh(const TriangleMesh& mesh, const Pose3& T) {
  TriangleMesh out = mesh;
  for (auto& v : out.vertices) v = T * v;
  return out;
}

void append_mesh(TriangleMesh* into, const TriangleMesh& mesh) {
  const int offset = static_cast<int>(into->vertices.size());
  into->vertices.insert(into->vertices.end(), mesh.vertices.begin(), mesh.vertices.end());
  for (const auto& f : mesh.faces) into->faces.push_back(f + Eigen::Vector3i::Constant(offset));
}

double mesh_signed_volume(const TriangleMesh& mesh) {
  double volume = 0.0;
  for (const auto& f : mesh.faces)
    volume += mesh.vertices[f[0]].dot(mesh.vertices[f[1]].cross(mesh.vertices[f[2]])) / 6.0;
  return volume;
}

}  // namespace keel::sim
