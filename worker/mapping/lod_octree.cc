#include "worker/mapping/lod_octree.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <unordered_map>

namespace keel::mapping {
namespace {

void check_attributes(const LodPoints& points) {
  for (const auto& attribute : points.attributes)
    if (attribute.size() != points.xyz.size())
      throw std::invalid_argument("lod: an attribute has " + std::to_string(attribute.size()) +
                                  " values for " + std::to_string(points.xyz.size()) + " points");
}

int child_index(const Eigen::Vector3f& p, const Eigen::Vector3d& center) {
  return (p.x() >= center.x() ? 1 : 0) | (p.y() >= center.y() ? 2 : 0) |
         (p.z() >= center.z() ? 4 : 0);
}

}  // namespace

LodPoints LodPoints::with_attributes(size_t attribute_count) {
  LodPoints points;
  points.attributes.resize(attribute_count);
  return points;
}

void LodPoints::push_back(const LodPoints& from, size_t index) {
  xyz.push_back(from.xyz[index]);
  for (size_t a = 0; a < attributes.size(); ++a) attributes[a].push_back(from.attributes[a][index]);
}

void LodPoints::append(const LodPoints& from) {
  if (from.attributes.size() != attributes.size())
    throw std::invalid_argument("lod: appending points with " +
                                std::to_string(from.attributes.size()) + " attributes to " +
                                std::to_string(attributes.size()));
  xyz.insert(xyz.end(), from.xyz.begin(), from.xyz.end());
  for (size_t a = 0; a < attributes.size(); ++a)
    attributes[a].insert(attributes[a].end(), from.attributes[a].begin(), from.attributes[a].end());
}

LodCube LodCube::child(int index) const {
  const double half = edge_m / 2;
  return LodCube{min + Eigen::Vector3d((index & 1) ? half : 0.0, (index & 2) ? half : 0.0,
                                       (index & 4) ? half : 0.0),
                 half};
}

LodPoints thin_points(const LodPoints& points, const LodCube& cube, int cells_per_edge) {
  check_attributes(points);
  if (cells_per_edge < 1 || cells_per_edge > 1024)
    throw std::invalid_argument("lod: cells per edge must lie in [1, 1024], got " +
                                std::to_string(cells_per_edge));
  const double cell = cube.edge_m / cells_per_edge;
  const double inverse_cell = 1.0 / cell;
  struct Best {
    uint32_t index;
    double distance2;
  };
  std::unordered_map<uint32_t, Best> best;
  best.reserve(std::min<size_t>(points.size(), size_t{1} << 20));
  for (size_t k = 0; k < points.size(); ++k) {
    const Eigen::Vector3d p = points.xyz[k].cast<double>();
    uint32_t key = 0;
    double distance2 = 0.0;
    for (int axis = 2; axis >= 0; --axis) {
      const double scaled = (p[axis] - cube.min[axis]) * inverse_cell;
      const int c = std::clamp(static_cast<int>(std::floor(scaled)), 0, cells_per_edge - 1);
      const double offset = scaled - (c + 0.5);
      distance2 += offset * offset;
      key = key * static_cast<uint32_t>(cells_per_edge) + static_cast<uint32_t>(c);
    }
    const auto [it, inserted] = best.try_emplace(key, Best{static_cast<uint32_t>(k), distance2});
    if (!inserted && distance2 < it->second.distance2)
      it->second = {static_cast<uint32_t>(k), distance2};
  }
  std::vector<uint8_t> chosen(points.size(), 0);
  for (const auto& [key, b] : best) chosen[b.index] = 1;
  LodPoints out = LodPoints::with_attributes(points.attributes.size());
  out.xyz.reserve(best.size());
  for (auto& attribute : out.attributes) attribute.reserve(best.size());
  for (size_t k = 0; k < points.size(); ++k)
    if (chosen[k]) out.push_back(points, k);
  return out;
}

LodPoints build_lod_subtree(const std::string& name, const LodCube& cube, LodPoints points,
                            const LodOptions& options, const LodWrite& write, LodNode* node) {
  check_attributes(points);
  LodNode self{name, cube, 0.0, {}, 0};
  if (points.size() <= options.max_points_per_tile || cube.edge_m / 2 < options.min_edge_m) {
    self.points = points.size();
    write(self, points);
    if (node) *node = self;
    return points;
  }
  // Split into the 8 children; each child's points, then the coarser thinning of theirs.
  std::vector<std::pair<int, LodPoints>> children;
  {
    std::vector<LodPoints> parts(8, LodPoints::with_attributes(points.attributes.size()));
    const Eigen::Vector3d center = cube.center();
    for (size_t k = 0; k < points.size(); ++k)
      parts[child_index(points.xyz[k], center)].push_back(points, k);
    points = LodPoints{};  // the parts hold them now
    for (int c = 0; c < 8; ++c) {
      if (parts[c].size() == 0) continue;
      LodPoints child_points = std::move(parts[c]);
      children.emplace_back(c, build_lod_subtree(name + std::to_string(c), cube.child(c),
                                                 std::move(child_points), options, write, nullptr));
    }
  }
  return build_lod_parent(name, cube, children, options, write, node);
}

LodPoints build_lod_parent(const std::string& name, const LodCube& cube,
                           const std::vector<std::pair<int, LodPoints>>& children,
                           const LodOptions& options, const LodWrite& write, LodNode* node) {
  if (children.empty()) throw std::invalid_argument("lod: node " + name + " has no children");
  LodPoints merged = LodPoints::with_attributes(children.front().second.attributes.size());
  LodNode self{name, cube, cube.edge_m / options.cells_per_edge, {}, 0};
  for (const auto& [index, points] : children) {
    merged.append(points);
    self.children.push_back(index);
  }
  LodPoints thinned = thin_points(merged, cube, options.cells_per_edge);
  self.points = thinned.size();
  write(self, thinned);
  if (node) *node = self;
  return thinned;
}

}  // namespace keel::mapping
