// 3D Tiles point-cloud tilesets (issue 17), read back with a reader written from the published
// specification (pnts_reader.h) after GNU tar unpacks them: the finest tiles hold every point
// of the map exactly once (within the quantization's half step), each coarser tile's points are
// a subset of its children's, bounding boxes hold their content, attributes come back exactly,
// and the header layout follows the specification.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <random>
#include <set>

#include "tests/worker/io/pnts_reader.h"
#include "worker/io/cloud/tileset_writer.h"
#include "worker/mapping/lod_octree.h"

namespace keel::io {
namespace {

namespace fs = std::filesystem;

fs::path temp_dir(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("keel_tileset_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

TEST(Pnts, HeaderAndBodiesFollowTheSpecification) {
  const std::vector<Eigen::Vector3f> xyz = {{1.f, 2.f, 3.f}, {1.5f, 2.f, 3.25f}, {2.f, 3.f, 4.f}};
  const std::string bytes = encode_pnts(
      xyz, Eigen::Vector3d(1, 2, 3), 1.0,
      {{"intensity", PntsAttribute::Type::kFloat}, {"sensor", PntsAttribute::Type::kUnsignedByte}},
      {{10.f, 20.5f, 30.f}, {0.f, 2.f, 1.f}});
  const testing::PntsContent content = testing::read_pnts(bytes, "tile");
  ASSERT_EQ(content.positions.size(), 3u);
  // Quantized on the cube [1, 2] x [2, 3] x [3, 4]: corners exact, 0.25 within half a step.
  EXPECT_NEAR((content.positions[0] - Eigen::Vector3d(1, 2, 3)).norm(), 0.0, 1e-12);
  EXPECT_NEAR(content.positions[1].x(), 1.5, 0.5 / 65535);
  EXPECT_NEAR(content.positions[1].z(), 3.25, 0.5 / 65535);
  EXPECT_NEAR((content.positions[2] - Eigen::Vector3d(2, 3, 4)).norm(), 0.0, 1e-12);
  EXPECT_EQ(content.properties.at("intensity"), (std::vector<double>{10.0, 20.5, 30.0}));
  EXPECT_EQ(content.properties.at("sensor"), (std::vector<double>{0, 2, 1}));
  EXPECT_EQ(content.batch_table["sensor"]["componentType"], "UNSIGNED_BYTE");

  EXPECT_THROW(encode_pnts(xyz, Eigen::Vector3d::Zero(), 1.0,
                           {{"sensor", PntsAttribute::Type::kUnsignedByte}}, {{0.f, 256.f, 1.f}}),
               std::invalid_argument);
  EXPECT_THROW(encode_pnts(xyz, Eigen::Vector3d::Zero(), 1.0,
                           {{"intensity", PntsAttribute::Type::kFloat}}, {{0.f}}),
               std::invalid_argument);
}

TEST(Tileset, EveryPointInExactlyOneFinestTileAndCoarserTilesAreSubsets) {
  // 50,000 points on two planes crossing an 18 m cube; id and intensity per point.
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.f, 16.f);
  std::normal_distribution<float> noise(0.f, 0.01f);
  mapping::LodPoints points = mapping::LodPoints::with_attributes(3);
  const size_t n = 50000;
  for (size_t k = 0; k < n; ++k) {
    const float a = u(rng), b = u(rng);
    points.xyz.push_back(k % 2 ? Eigen::Vector3f(100 + a, 200 + b, 5 + noise(rng))
                               : Eigen::Vector3f(100 + a, 208 + noise(rng), b));
    points.attributes[0].push_back(static_cast<float>(k));        // id
    points.attributes[1].push_back(static_cast<float>(k % 255));  // intensity
    points.attributes[2].push_back(static_cast<float>(k % 3));    // sensor
  }
  const fs::path dir = temp_dir("lod");
  const fs::path tar = dir / "tiles_test.tar";
  TilesetTarWriter writer(tar,
                          {{"id", PntsAttribute::Type::kFloat},
                           {"intensity", PntsAttribute::Type::kFloat},
                           {"sensor", PntsAttribute::Type::kUnsignedByte}},
                          {{"map", "test"}, {"sensors", {"a", "b", "c"}}});
  mapping::LodOptions options;
  options.max_points_per_tile = 4000;
  const mapping::LodCube cube{Eigen::Vector3d(100, 200, -1), 18.0};
  mapping::build_lod_subtree(
      "r", cube, points, options,
      [&](const mapping::LodNode& node, const mapping::LodPoints& content) {
        writer.add_tile(node.name, node.cube.min, node.cube.edge_m, node.geometric_error_m,
                        node.children, content.xyz, content.attributes);
      },
      nullptr);
  const nlohmann::json written = writer.finish("r");
  EXPECT_FALSE(fs::exists(tar.string() + ".partial"));

  const testing::Tileset tileset = testing::read_tileset_tar(tar, dir / "x");
  EXPECT_EQ(tileset.root, "r.pnts");
  EXPECT_EQ(tileset.json["root"]["refine"], "REPLACE");
  EXPECT_EQ(tileset.json["extras"]["keel"]["points"], n);
  EXPECT_EQ(tileset.json["extras"]["keel"]["tiles"], tileset.tiles.size());
  EXPECT_EQ(tileset.json["extras"]["keel"]["map"], "test");
  EXPECT_EQ(tileset.json["properties"]["intensity"]["maximum"], 254.0);
  EXPECT_EQ(tileset.json["extras"]["keel"]["attributes"]["sensor"]["max"], 2.0);
  EXPECT_GT(tileset.tiles.size(), 15u);
  EXPECT_GT(tileset.json["geometricError"].get<double>(),
            tileset.json["root"]["geometricError"].get<double>());

  std::vector<int> seen(n, 0);
  size_t finest_points = 0;
  for (const auto& [uri, tile] : tileset.tiles) {
    const auto& ids = tile.content.properties.at("id");
    const double half = tile.box[3];
    const Eigen::Vector3d center(tile.box[0], tile.box[1], tile.box[2]);
    for (size_t k = 0; k < ids.size(); ++k) {
      const size_t id = static_cast<size_t>(ids[k]);
      ASSERT_LT(id, n);
      // Where it was, within half a quantization step per axis, and inside the box.
      EXPECT_LE((tile.content.positions[k] - points.xyz[id].cast<double>()).cwiseAbs().maxCoeff(),
                2 * half / 65535 * 0.5 + 1e-9)
          << uri;
      EXPECT_LE((tile.content.positions[k] - center).cwiseAbs().maxCoeff(), half + 1e-9) << uri;
      EXPECT_EQ(tile.content.properties.at("intensity")[k], id % 255);
      EXPECT_EQ(tile.content.properties.at("sensor")[k], id % 3);
    }
    if (tile.children.empty()) {
      EXPECT_EQ(tile.geometric_error, 0.0);
      EXPECT_LE(ids.size(), options.max_points_per_tile);
      finest_points += ids.size();
      for (const double id : ids) ++seen[static_cast<size_t>(id)];
      continue;
    }
    EXPECT_GT(tile.geometric_error, 0.0);
    std::set<double> below;
    for (const auto& child : tile.children) {
      const auto& child_ids = tileset.tiles.at(child).content.properties.at("id");
      below.insert(child_ids.begin(), child_ids.end());
      EXPECT_LT(tileset.tiles.at(child).geometric_error, tile.geometric_error);
    }
    for (const double id : ids) EXPECT_TRUE(below.count(id)) << uri << " holds " << id;
  }
  EXPECT_EQ(finest_points, n);
  EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), static_cast<long>(n));  // exactly once each
  fs::remove_all(dir);
}

TEST(Tileset, AnUnfinishedTarLeavesNothing) {
  const fs::path dir = temp_dir("abandon");
  {
    TilesetTarWriter writer(dir / "t.tar", {}, nlohmann::json::object());
    writer.add_tile("r", Eigen::Vector3d::Zero(), 1.0, 0.0, {}, {{0.5f, 0.5f, 0.5f}}, {});
    EXPECT_THROW(writer.add_tile("q", Eigen::Vector3d::Zero(), 1.0, 0.1, {3}, {}, {}),
                 std::invalid_argument);  // child q3 was never added
  }
  EXPECT_TRUE(fs::is_empty(dir));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace keel::io
