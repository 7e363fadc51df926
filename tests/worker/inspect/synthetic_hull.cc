#include "tests/worker/inspect/synthetic_hull.h"

#include <algorithm>
#include <cmath>
#include <random>

namespace keel::inspect::testing {
namespace {

double clipped_noise(std::mt19937& rng, double sigma) {
  std::normal_distribution<double> normal(0.0, sigma);
  return std::clamp(normal(rng), -3.0 * sigma, 3.0 * sigma);
}

bool on_a_bump(const Eigen::Vector2d& xy, const std::vector<Bump>& bumps) {
  for (const Bump& bump : bumps) {
    if ((xy - bump.center_xy).norm() <= bump.radius_m) return true;
  }
  return false;
}

Landmark make_landmark(const Eigen::Vector2d& xy, double z, const SceneOptions& options) {
  Landmark landmark;
  landmark.point_world = Eigen::Vector3d(xy.x(), xy.y(), z);
  landmark.h_m = z;  // Eq. (5) for the plane z = 0 with normal +z
  // Eq. (7) with the paper's sigma0 = 1 m, sigma1 = 0.02 m, as the BA would label it: on the
  // model inside the switching distance 0.0561 m (worker/ba/surface_factor.h).
  landmark.lambda = std::abs(z) < 0.0561 ? 1 : 0;
  for (size_t v = 0; v < options.camera_xy.size(); ++v) {
    const Eigen::Vector2d d = (xy - options.camera_xy[v]).cwiseAbs();
    if (d.maxCoeff() <= options.half_footprint_m) landmark.views.push_back(static_cast<int>(v));
  }
  return landmark;
}

}  // namespace

TriangleMesh make_flat_patch(int nx, int ny, double spacing_m) {
  TriangleMesh mesh;
  const double x0 = -0.5 * (nx - 1) * spacing_m, y0 = -0.5 * (ny - 1) * spacing_m;
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i)
      mesh.vertices.emplace_back(x0 + i * spacing_m, y0 + j * spacing_m, 0.0);
  }
  for (int j = 0; j + 1 < ny; ++j) {
    for (int i = 0; i + 1 < nx; ++i) {
      const int a = j * nx + i, b = a + 1, c = a + nx, d = c + 1;
      mesh.faces.emplace_back(a, b, d);
      mesh.faces.emplace_back(a, d, c);
    }
  }
  return mesh;
}

Pose3 camera_looking_down(const Eigen::Vector2d& xy, double standoff_m) {
  Pose3 T_world_camera = Pose3::Identity();
  T_world_camera.linear() << 1, 0, 0,  //
      0, -1, 0,                        //
      0, 0, -1;                        // columns: camera x, y, z axes in the world
  T_world_camera.translation() = Eigen::Vector3d(xy.x(), xy.y(), standoff_m);
  return T_world_camera;
}

InspectInput make_scene(const SceneOptions& options) {
  InspectInput input;
  input.cad_in_world = make_flat_patch(options.nx, options.ny, options.spacing_m);
  for (const Eigen::Vector2d& xy : options.camera_xy) {
    input.T_world_camera.push_back(camera_looking_down(xy, options.standoff_m));
  }
  std::mt19937 rng(options.seed);
  const double half_x = 0.5 * (options.nx - 1) * options.spacing_m;
  const double half_y = 0.5 * (options.ny - 1) * options.spacing_m;
  std::uniform_real_distribution<double> ux(-half_x, half_x), uy(-half_y, half_y);
  while (static_cast<int>(input.landmarks.size()) < options.num_hull_landmarks) {
    const Eigen::Vector2d xy(ux(rng), uy(rng));
    if (on_a_bump(xy, options.bumps)) continue;  // the object hides the hull there
    input.landmarks.push_back(make_landmark(xy, clipped_noise(rng, options.hull_noise_m), options));
  }
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (const Bump& bump : options.bumps) {
    for (int k = 0; k < bump.num_landmarks; ++k) {
      const double r = bump.radius_m * std::sqrt(unit(rng)), phi = 2.0 * M_PI * unit(rng);
      const Eigen::Vector2d xy = bump.center_xy + r * Eigen::Vector2d(std::cos(phi), std::sin(phi));
      const double z = bump.height_m + clipped_noise(rng, options.bump_noise_m);
      input.landmarks.push_back(make_landmark(xy, z, options));
    }
  }
  return input;
}

}  // namespace keel::inspect::testing
