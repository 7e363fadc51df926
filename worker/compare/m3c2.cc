#include "worker/compare/m3c2.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <tuple>
#include <unordered_set>
#include <utility>

#include "core/parallel_for.h"

namespace keel::compare {
namespace {

void require(bool ok, const char* field, const char* expected) {
  if (!ok) throw std::invalid_argument(std::string(field) + ": expected " + expected);
}

// Moments of the voxels whose mean lies within `radius` of `at`.
Moments gather(const VoxelMoments& voxels, const NearestIndex& index, const Eigen::Vector3f& at,
               double radius, std::vector<uint32_t>* scratch) {
  index.within(at, radius, scratch);
  Moments sum;
  for (const uint32_t v : *scratch) sum.add(voxels.voxels[v]);
  return sum;
}

struct Projection {
  double sum = 0.0, sum_squares = 0.0;
  uint32_t count = 0;
};

// Adds v's projection on the normal when v (a point minus the core) is inside the cylinder.
void add_if_inside(const Eigen::Vector3d& v, const Eigen::Vector3d& normal, double r2, double depth,
                   Projection* p) {
  const double t = v.dot(normal);
  if (std::abs(t) > depth || v.squaredNorm() - t * t > r2) return;
  p->sum += t;
  p->sum_squares += t * t;
  ++p->count;
}

// Points of `cloud` in the cylinder of radius r and half-length `depth` about core + t n.
Projection project(const NearestIndex& cloud, const Eigen::Vector3d& core,
                   const Eigen::Vector3d& normal, double radius, double depth,
                   std::vector<uint32_t>* scratch) {
  cloud.within(core.cast<float>(), std::sqrt(radius * radius + depth * depth), scratch);
  Projection p;
  for (const uint32_t i : *scratch)
    add_if_inside(cloud.point(i).cast<double>() - core, normal, radius * radius, depth, &p);
  return p;
}

// The same from a grid: the points of the cells along the cylinder's axis.
Projection project(const PointGrid& cloud, const Eigen::Vector3d& core,
                   const Eigen::Vector3d& normal, double radius, double depth,
                   std::vector<PointGrid::Run>* scratch) {
  cloud.near_segment(core - depth * normal, core + depth * normal, radius, scratch);
  Projection p;
  const std::vector<Eigen::Vector3f>& points = cloud.points();
  for (const PointGrid::Run& run : *scratch)
    for (uint32_t i = run.begin; i < run.end; ++i)
      add_if_inside(points[i].cast<double>() - core, normal, radius * radius, depth, &p);
  return p;
}

// The two clouds' projections, from the grids when the clouds have them.
struct Cylinders {
  const M3c2Clouds& clouds;
  std::vector<uint32_t> indices;
  std::vector<PointGrid::Run> runs;

  std::pair<Projection, Projection> project_both(const Eigen::Vector3d& core,
                                                 const Eigen::Vector3d& normal, double radius,
                                                 double depth) {
    if (clouds.reference_grid && clouds.compared_grid)
      return {project(*clouds.reference_grid, core, normal, radius, depth, &runs),
              project(*clouds.compared_grid, core, normal, radius, depth, &runs)};
    return {project(*clouds.reference, core, normal, radius, depth, &indices),
            project(*clouds.compared, core, normal, radius, depth, &indices)};
  }
};

double sample_sigma(const Projection& p) {
  if (p.count < 2) return 0.0;
  const double mean = p.sum / p.count;
  return std::sqrt(std::max(0.0, (p.sum_squares - p.count * mean * mean) / (p.count - 1)));
}

// The voxels of A that hold points (its normals' voxel grid): a line of sight from a core
// point to a viewpoint that crosses one passes through structure, as a view from one side of
// a pier to the other face does.
class Occupancy {
 public:
  explicit Occupancy(const VoxelMoments& voxels) : cell_m_(voxels.voxel_m) {
    keys_.reserve(voxels.means.size());
    for (const Eigen::Vector3f& mean : voxels.means) keys_.insert(key(mean.cast<double>()));
  }
  // Whether [from + start u, from + end u] (u a unit vector) meets an occupied voxel, sampled
  // every 0.8 voxel so a surface's layer of voxels, at least one voxel thick, is not stepped over.
  bool blocked(const Eigen::Vector3d& from, const Eigen::Vector3d& u, double start,
               double end) const {
    for (double t = start; t < end; t += 0.8 * cell_m_)
      if (keys_.count(key(from + t * u))) return true;
    return false;
  }

 private:
  uint64_t key(const Eigen::Vector3d& p) const {
    auto axis = [&](double v) {
      return uint64_t(int64_t(std::floor(v / cell_m_)) + (1 << 20)) & 0x1fffff;
    };
    return axis(p.x()) << 42 | axis(p.y()) << 21 | axis(p.z());
  }
  double cell_m_;
  std::unordered_set<uint64_t> keys_;
};

// Faces n towards the sensor that saw the surface: the nearest viewpoint within kViewRadiusM
// that looks at it within 60 degrees of its normal (|n . u| >= 0.5), as a range sensor sees a
// surface, and whose line of sight does not cross A's structure within kOcclusionDepthM (a
// viewpoint beyond a pier, nearer than the one that saw this face, would otherwise turn the
// normal into the pier and a spall into a gain); a grazing view through a gap between piers,
// nearer but sideways, does not decide. Failing that the nearest of those viewpoints decides,
// then the nearest viewpoint.
constexpr double kViewRadiusM = 30.0;
constexpr double kOcclusionDepthM = 6.0;  // thicker than a pier or a hull's frames
constexpr double kOwnSurfaceM = 0.5;      // the line of sight leaves the core's own voxels first
constexpr int kViewsTried = 4;

Eigen::Vector3d oriented(Eigen::Vector3d n, const Eigen::Vector3d& core,
                         const NearestIndex* viewpoints, const Occupancy* occupancy,
                         std::vector<uint32_t>* scratch) {
  if (viewpoints) {
    viewpoints->within(core.cast<float>(), kViewRadiusM, scratch);
    std::vector<std::pair<double, uint32_t>> facing;  // (distance, viewpoint) within 60 degrees
    for (const uint32_t v : *scratch) {
      const Eigen::Vector3d to = viewpoints->point(v).cast<double>() - core;
      const double d = to.norm();
      if (d > 0.0 && std::abs(n.dot(to)) >= 0.5 * d) facing.emplace_back(d, v);
    }
    const size_t tried = std::min<size_t>(facing.size(), kViewsTried);
    std::partial_sort(facing.begin(), facing.begin() + tried, facing.end());
    auto side_of = [&](uint32_t v) { return n.dot(viewpoints->point(v).cast<double>() - core); };
    double side = tried > 0 ? side_of(facing[0].second) : 0.0;  // the nearest, if all are hidden
    for (size_t k = 0; k < tried && occupancy; ++k) {
      const auto [d, v] = facing[k];
      const Eigen::Vector3d u = (viewpoints->point(v).cast<double>() - core) / d;
      if (!occupancy->blocked(core, u, kOwnSurfaceM, std::min(d, kOcclusionDepthM))) {
        side = side_of(v);
        break;
      }
    }
    if (side == 0.0) {
      const Neighbour v = viewpoints->nearest(core.cast<float>());
      side = n.dot(viewpoints->point(v.index).cast<double>() - core);
    }
    return side < 0.0 ? Eigen::Vector3d(-n) : n;
  }
  for (int axis : {2, 0, 1}) {
    if (std::abs(n[axis]) > 1e-9) return n[axis] < 0.0 ? Eigen::Vector3d(-n) : n;
  }
  return n;
}

}  // namespace

void validate(const M3c2Options& o) {
  require(std::isfinite(o.normal_scale_m) && o.normal_scale_m > 0, "normal_scale_m", "> 0");
  require(std::isfinite(o.projection_scale_m) && o.projection_scale_m > 0, "projection_scale_m",
          "> 0");
  require(std::isfinite(o.max_depth_m) && o.max_depth_m > 0, "max_depth_m", "> 0");
  require(std::isfinite(o.core_spacing_m) && o.core_spacing_m > 0, "core_spacing_m", "> 0");
  require(o.min_points >= 2, "min_points", "an integer >= 2");
  require(std::isfinite(o.registration_error_m) && o.registration_error_m >= 0,
          "registration_error_m", ">= 0");
  require(std::isfinite(o.confidence_z) && o.confidence_z > 0, "confidence_z", "> 0");
}

void apply_registration_error(std::vector<CoreChange>* cores, double registration_error_m,
                              double confidence_z) {
  for (CoreChange& c : *cores) {
    if (!c.defined()) continue;
    c.lod95_m = float(confidence_z * (c.statistical_m + registration_error_m));
    c.significant = std::abs(c.distance_m) > c.lod95_m;
  }
}

void apply_registration_errors(std::vector<CoreChange>* cores,
                               const std::vector<double>& registration_error_m, double confidence_z,
                               const std::vector<double>& significance_reg_m,
                               double significance_z) {
  if (registration_error_m.size() != cores->size() || significance_reg_m.size() != cores->size())
    throw std::invalid_argument("registration errors: expected one per core point");
  for (size_t i = 0; i < cores->size(); ++i) {
    CoreChange& c = (*cores)[i];
    if (!c.defined()) continue;
    c.lod95_m = float(confidence_z * (c.statistical_m + registration_error_m[i]));
    c.significant =
        std::abs(c.distance_m) > significance_z * (c.statistical_m + significance_reg_m[i]);
  }
}

std::vector<CoreChange> m3c2(const M3c2Clouds& clouds, const std::vector<Eigen::Vector3f>& cores,
                             const std::vector<Eigen::Vector3f>& viewpoints,
                             const M3c2Options& options) {
  validate(options);
  const bool grids = clouds.reference_grid && clouds.compared_grid;
  if (!(grids || (clouds.reference && clouds.compared)) || !clouds.reference_voxels ||
      !clouds.compared_voxels)
    throw std::invalid_argument("m3c2: both clouds and their voxel moments are needed");
  const NearestIndex reference_voxels(clouds.reference_voxels->means);
  const NearestIndex compared_voxels(clouds.compared_voxels->means);
  // Viewpoints thinned to one per metre: a trajectory's thousands of poses vote as places.
  std::unique_ptr<NearestIndex> views;
  std::unique_ptr<Occupancy> occupancy;
  if (!viewpoints.empty()) {
    views = std::make_unique<NearestIndex>(voxelize(viewpoints, 1.0).means);
    occupancy = std::make_unique<Occupancy>(*clouds.reference_voxels);
  }

  const double normal_radius = 0.5 * options.normal_scale_m;
  const double radius = 0.5 * options.projection_scale_m;
  // Most cylinders find both surfaces close to the core point: a short search first, the full
  // depth only when a cloud has too few points in it (a large change).
  const double short_depth = std::min(options.max_depth_m, std::max(0.25, 2.0 * radius));
  const double s2 = options.core_spacing_m * options.core_spacing_m;

  std::vector<CoreChange> out(cores.size());
  keel::parallel_for(cores.size(), options.threads, [&](size_t begin, size_t end) {
    std::vector<uint32_t> scratch;
    Cylinders cylinders{clouds, {}, {}};
    for (size_t i = begin; i < end; ++i) {
      if (options.check_canceled && (i - begin) % 4096 == 0) options.check_canceled();
      CoreChange& c = out[i];
      c.position = cores[i];
      const Eigen::Vector3d core = cores[i].cast<double>();
      // Step 1: the normal, from A (B where A has too few points: new structure).
      LocalPlane plane = fit_plane(
          gather(*clouds.reference_voxels, reference_voxels, cores[i], normal_radius, &scratch));
      if (!plane.valid)
        plane = fit_plane(
            gather(*clouds.compared_voxels, compared_voxels, cores[i], normal_radius, &scratch));
      if (!plane.valid) continue;
      const Eigen::Vector3d n =
          oriented(plane.normal, core, views.get(), occupancy.get(), &scratch);
      c.normal = n.cast<float>();
      c.area_m2 = float(s2 / n.lpNorm<1>());
      // Step 2: the cylinders.
      auto [a, b] = cylinders.project_both(core, n, radius, short_depth);
      if ((a.count < uint32_t(options.min_points) || b.count < uint32_t(options.min_points)) &&
          options.max_depth_m > short_depth)
        std::tie(a, b) = cylinders.project_both(core, n, radius, options.max_depth_m);
      c.count_a = a.count;
      c.count_b = b.count;
      if (a.count < uint32_t(options.min_points) || b.count < uint32_t(options.min_points))
        continue;
      // Steps 3-4.
      const double sigma_a = sample_sigma(a), sigma_b = sample_sigma(b);
      const double distance = b.sum / b.count - a.sum / a.count;
      const double statistical =
          std::sqrt(sigma_a * sigma_a / a.count + sigma_b * sigma_b / b.count);
      const double lod = options.confidence_z * (statistical + options.registration_error_m);
      c.statistical_m = float(statistical);
      c.sigma_a_m = float(sigma_a);
      c.sigma_b_m = float(sigma_b);
      c.distance_m = float(distance);
      c.lod95_m = float(lod);
      c.significant = std::abs(distance) > lod;
    }
  });
  return out;
}

}  // namespace keel::compare
