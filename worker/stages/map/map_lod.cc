#include "worker/stages/map/map_lod.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <climits>
#include <cmath>
#include <set>
#include <stdexcept>
#include <tuple>

namespace keel::pipeline {
namespace {

int64_t floor_div(int64_t a, int64_t b) {
  const int64_t q = a / b;
  return (a % b != 0 && a < 0) ? q - 1 : q;
}

// A cube of the octree: `level` relative to the grid's tiles (0: a tile, < 0: coarser, > 0: a
// split tile's children), integer coordinates at that level counted from the lowest tile
// corner (Builder::origin_), so that they are >= 0 and the parents of any two cubes meet (with
// signed coordinates, -1 and 0 would stay apart at every level).
struct Node {
  int level = 0;
  int64_t x = 0, y = 0, z = 0;
  bool operator<(const Node& o) const {
    return std::tie(level, x, y, z) < std::tie(o.level, o.x, o.y, o.z);
  }
  Node parent() const { return Node{level - 1, floor_div(x, 2), floor_div(y, 2), floor_div(z, 2)}; }
  Node child(int index) const {
    return Node{level + 1, 2 * x + (index & 1), 2 * y + ((index >> 1) & 1),
                2 * z + ((index >> 2) & 1)};
  }
};

class Builder {
 public:
  Builder(const mapping::TileGrid& grid, const LodTileSource& source,
          const mapping::LodOptions& options, io::TilesetTarWriter& writer,
          const std::function<void()>& check_canceled)
      : grid_(grid),
        source_(source),
        options_(options),
        writer_(writer),
        check_canceled_(check_canceled) {
    origin_.fill(INT64_MAX);
    for (const auto& tile : source.tiles) {
      const int64_t scale = int64_t{1} << tile.level;
      origin_[0] = std::min(origin_[0], floor_div(tile.x, scale));
      origin_[1] = std::min(origin_[1], floor_div(tile.y, scale));
      origin_[2] = std::min(origin_[2], floor_div(tile.z, scale));
    }
    for (const auto& tile : source.tiles) {
      const int64_t scale = int64_t{1} << tile.level;
      tiles_.insert(Node{tile.level, tile.x - origin_[0] * scale, tile.y - origin_[1] * scale,
                         tile.z - origin_[2] * scale});
    }
    // Every ancestor of a tile down to level 0; the root is the first level at which they meet.
    std::set<Node> level0;
    for (Node node : tiles_) {
      while (node.level > 0) {
        occupied_.insert(node);
        node = node.parent();
      }
      level0.insert(node);
    }
    std::set<Node> current = level0;
    while (true) {
      occupied_.insert(current.begin(), current.end());
      if (current.size() == 1) break;
      std::set<Node> parents;
      for (const Node& n : current) parents.insert(n.parent());
      current = std::move(parents);
    }
    root_ = *current.begin();
  }

  void build() { build(root_, "r"); }

 private:
  mapping::LodCube cube(const Node& node) const {
    const double tile_edge = grid_.edge_m(0);
    const double edge = tile_edge * std::ldexp(1.0, -node.level);
    return mapping::LodCube{
        Eigen::Vector3d(static_cast<double>(origin_[0]) * tile_edge + node.x * edge,
                        static_cast<double>(origin_[1]) * tile_edge + node.y * edge,
                        static_cast<double>(origin_[2]) * tile_edge + node.z * edge),
        edge};
  }

  mapping::TileKey tile_key(const Node& node) const {
    const int64_t scale = int64_t{1} << node.level;
    return mapping::TileKey{static_cast<int32_t>(node.x + origin_[0] * scale),
                            static_cast<int32_t>(node.y + origin_[1] * scale),
                            static_cast<int32_t>(node.z + origin_[2] * scale),
                            static_cast<uint8_t>(node.level)};
  }

  void write(const mapping::LodNode& node, const mapping::LodPoints& points) {
    if (check_canceled_) check_canceled_();
    writer_.add_tile(node.name, node.cube.min, node.cube.edge_m, node.geometric_error_m,
                     node.children, points.xyz, points.attributes);
  }

  mapping::LodPoints build(const Node& node, const std::string& name) {
    const mapping::LodWrite write = [this](const mapping::LodNode& n, const mapping::LodPoints& p) {
      this->write(n, p);
    };
    if (tiles_.count(node))
      return mapping::build_lod_subtree(name, cube(node), source_.load(tile_key(node)), options_,
                                        write, nullptr);
    std::vector<std::pair<int, mapping::LodPoints>> children;
    for (int c = 0; c < 8; ++c) {
      const Node child = node.child(c);
      if (occupied_.count(child)) children.emplace_back(c, build(child, name + std::to_string(c)));
    }
    return mapping::build_lod_parent(name, cube(node), children, options_, write, nullptr);
  }

  const mapping::TileGrid& grid_;
  const LodTileSource& source_;
  const mapping::LodOptions& options_;
  io::TilesetTarWriter& writer_;
  const std::function<void()>& check_canceled_;
  std::array<int64_t, 3> origin_;  // the lowest level-0 tile coordinates
  std::set<Node> tiles_, occupied_;
  Node root_;
};

}  // namespace

MapTilesetResult write_map_tileset(const std::filesystem::path& tar, const mapping::TileGrid& grid,
                                   const LodTileSource& source,
                                   const std::vector<io::PntsAttribute>& attributes,
                                   nlohmann::json extras, const mapping::LodOptions& options,
                                   const std::function<void()>& check_canceled) {
  if (source.tiles.empty())
    throw std::invalid_argument("tileset " + tar.filename().string() + ": the map has no tiles");
  const auto start = std::chrono::steady_clock::now();
  io::TilesetTarWriter writer(tar, attributes, std::move(extras));
  Builder(grid, source, options, writer, check_canceled).build();
  MapTilesetResult result;
  result.tileset = writer.finish("r");
  result.tiles = writer.tiles();
  result.points = writer.points();
  result.bytes = std::filesystem::file_size(tar);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace keel::pipeline
