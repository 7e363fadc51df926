// bench_texture: how much of each foreign object of a keel-sim hauv-hull survey carries texture,
// that is, what any method that measures the surface from its images (sparse features, dense
// stereo) could see of it. keel-sim paints the hull and its objects with blobs (truth
// landmarks.csv: centre and radius_m; HullWorld::albedo_at paints every surface point within
// radius_m of a centre); between blobs there is only a faint grain. For each object it prints
// the blobs on it and its highest textured point (the object's surface sampled every 1 mm
// radially and 128 times around, against every blob near it), so the height a texture-based
// measurement can reach is known before judging one. With --before (the first survey of the
// scene) and this survey's `changes`, each grown patch's growth as its textured tops measure it,
// against the true growth: the best a texture-based growth measurement can do (issue 16's
// target is 1.5 cm). Optimistic: a blob's soft rim (the outer 30 % of its radius) counts as
// texture to its edge.
// Usage: bench_texture --mission DIR [--before DIR]
#include <yaml-cpp/yaml.h>
#include <CLI/CLI.hpp>

#include <Eigen/Geometry>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

struct Blob {
  Eigen::Vector3d center;
  double radius_m = 0.0;
};

struct Object {
  std::string kind;  // "patch" (raised cosine) or "cylinder"
  Eigen::Vector3d center, axis;
  double radius_m = 0.0, height_m = 0.0;
};

Eigen::Vector3d vec(const YAML::Node& n) {
  return {n[0].as<double>(), n[1].as<double>(), n[2].as<double>()};
}

std::vector<Blob> read_blobs(const std::string& mission) {
  const std::string path = mission + "/ground_truth/landmarks.csv";
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open");
  std::string line;
  std::getline(in, line);
  if (line != "id,x,y,z,on_cad,radius_m")
    throw std::runtime_error(path +
                             ": expected the header id,x,y,z,on_cad,radius_m (a keel-sim "
                             "that writes blob radii), got '" +
                             line + "'");
  std::vector<Blob> blobs;
  while (std::getline(in, line)) {
    std::stringstream fields(line);
    std::string v[6];
    for (auto& f : v) std::getline(fields, f, ',');
    blobs.push_back({{std::stod(v[1]), std::stod(v[2]), std::stod(v[3])}, std::stod(v[5])});
  }
  return blobs;
}

Object read_object(const YAML::Node& n) {
  Object o;
  o.kind = n["kind"].as<std::string>();
  o.center = vec(n["center"]);
  o.axis = vec(n["normal"] ? n["normal"] : n["axis"]).normalized();
  o.radius_m = n["radius"].as<double>();
  o.height_m = n["height"].as<double>();
  return o;
}

std::vector<Object> read_objects(const std::string& mission) {
  const YAML::Node truth = YAML::LoadFile(mission + "/ground_truth/truth.yaml");
  std::vector<Object> out;
  for (const auto& n : truth["foreign_objects"]) out.push_back(read_object(n));
  return out;
}

// The raised-cosine fouling profile keel-sim builds (hull_model.cc, foreign_object_mesh).
double patch_height(const Object& o, double rho) {
  return rho >= o.radius_m ? 0.0 : 0.5 * o.height_m * (1.0 + std::cos(M_PI * rho / o.radius_m));
}

struct Texture {
  int blobs_on = 0;     // blob centres on the object (within its radius, above its base)
  double top_m = -1.0;  // highest textured point along the axis; -1: none
};

Texture texture_of(const Object& o, const std::vector<Blob>& all) {
  Eigen::Vector3d u = o.axis.cross(std::abs(o.axis.x()) < 0.9 ? Eigen::Vector3d::UnitX()
                                                              : Eigen::Vector3d::UnitY());
  u.normalize();
  const Eigen::Vector3d w = o.axis.cross(u);
  std::vector<Blob> near;
  Texture t;
  for (const Blob& b : all) {
    const Eigen::Vector3d d = b.center - o.center;
    const double along = d.dot(o.axis), lateral = (d - along * o.axis).norm();
    if (lateral > o.radius_m + b.radius_m || along < -0.05 || along > o.height_m + 0.05) continue;
    near.push_back(b);
    t.blobs_on += lateral <= o.radius_m && along > 0.002;
  }
  const auto textured = [&](const Eigen::Vector3d& p) {
    for (const Blob& b : near)
      if ((p - b.center).norm() < b.radius_m) return true;
    return false;
  };
  constexpr int kAround = 128;
  const int radial = static_cast<int>(std::ceil(o.radius_m / 0.001));
  for (int k = 0; k < kAround; ++k) {
    const double phi = 2.0 * M_PI * k / kAround;
    const Eigen::Vector3d dir = std::cos(phi) * u + std::sin(phi) * w;
    for (int i = 0; i <= radial; ++i) {
      const double rho = o.radius_m * i / radial;
      const double h = o.kind == "cylinder" ? o.height_m : patch_height(o, rho);
      if (h > t.top_m && textured(o.center + rho * dir + h * o.axis)) t.top_m = h;
    }
    if (o.kind == "cylinder")  // the side wall, bottom to top
      for (double h = 0.0; h <= o.height_m; h += 0.001)
        if (h > t.top_m && textured(o.center + o.radius_m * dir + h * o.axis)) t.top_m = h;
  }
  return t;
}

// The object of `objects` whose centre is nearest `center` (within 5 cm), or nullptr.
const Object* at(const std::vector<Object>& objects, const Eigen::Vector3d& center) {
  for (const Object& o : objects)
    if ((o.center - center).norm() < 0.05) return &o;
  return nullptr;
}

}  // namespace

int main(int argc, char** argv) {
  std::string mission, before;
  CLI::App app{"bench_texture: the textured share of a keel-sim hull survey's foreign objects"};
  app.add_option("--mission", mission)->required();
  app.add_option("--before", before, "the scene's first survey: growth of its grown patches");
  CLI11_PARSE(app, argc, argv);
  try {
    const std::vector<Blob> blobs = read_blobs(mission);
    const std::vector<Object> objects = read_objects(mission);
    std::printf("%s: %zu blobs, %zu foreign objects\n", mission.c_str(), blobs.size(),
                objects.size());
    for (const Object& o : objects) {
      const Texture t = texture_of(o, blobs);
      std::printf(
          "  %-8s r %.3f h %.4f: %2d blobs on it, textured to %.4f m (%.0f %% of its "
          "height, %.4f m short)\n",
          o.kind.c_str(), o.radius_m, o.height_m, t.blobs_on, t.top_m, 100.0 * t.top_m / o.height_m,
          o.height_m - t.top_m);
    }
    if (before.empty()) return 0;
    const std::vector<Blob> blobs_a = read_blobs(before);
    const std::vector<Object> objects_a = read_objects(before);
    const YAML::Node truth = YAML::LoadFile(mission + "/ground_truth/truth.yaml");
    int grown = 0, within = 0;
    for (const auto& c : truth["changes"]) {
      if (c["kind"].as<std::string>() != "grown") continue;
      const Object* b = at(objects, vec(c["center"]));
      const Object* a = at(objects_a, vec(c["center"]));
      if (!a || !b) throw std::runtime_error("a grown patch is missing from a survey's objects");
      const double top_a = texture_of(*a, blobs_a).top_m, top_b = texture_of(*b, blobs).top_m;
      const double growth = b->height_m - a->height_m, error = (top_b - top_a) - growth;
      ++grown;
      within += std::abs(error) <= 0.015;
      std::printf(
          "  grown +%.4f m: textured tops %.4f -> %.4f m, growth they show %+.4f m "
          "(error %+.4f)\n",
          growth, top_a, top_b, top_b - top_a, error);
    }
    std::printf("  growth within 1.5 cm from texture alone: %d of %d\n", within, grown);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_texture: %s\n", e.what());
    return 2;
  }
  return 0;
}
