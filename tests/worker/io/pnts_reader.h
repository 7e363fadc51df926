// A reader of 3D Tiles 1.0 point-cloud tiles written from the published specification
// (CesiumGS/3d-tiles, specification/TileFormats/PointCloud and FeatureTable/BatchTable), kept
// apart from Keel's writer so the tests check the files against the format, not against the
// code that wrote them. Checks the layout rules a strict reader relies on (8-byte alignment of
// the JSON headers and binary bodies, byteLength) and fails the test otherwise.
#pragma once

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <Eigen/Core>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace keel::testing {

struct PntsContent {
  std::vector<Eigen::Vector3d> positions;                 // RTC_CENTER / quantization applied
  std::map<std::string, std::vector<double>> properties;  // batch table, per point
  nlohmann::json feature_table, batch_table;
};

template <typename T>
T read_le(const std::string& bytes, size_t at) {
  T value;
  std::memcpy(&value, bytes.data() + at, sizeof(T));
  return value;
}

inline size_t component_bytes(const std::string& type) {
  if (type == "BYTE" || type == "UNSIGNED_BYTE") return 1;
  if (type == "SHORT" || type == "UNSIGNED_SHORT") return 2;
  if (type == "INT" || type == "UNSIGNED_INT" || type == "FLOAT") return 4;
  if (type == "DOUBLE") return 8;
  ADD_FAILURE() << "unknown componentType " << type;
  return 1;
}

inline double component_at(const std::string& bytes, size_t at, const std::string& type) {
  if (type == "BYTE") return read_le<int8_t>(bytes, at);
  if (type == "UNSIGNED_BYTE") return read_le<uint8_t>(bytes, at);
  if (type == "SHORT") return read_le<int16_t>(bytes, at);
  if (type == "UNSIGNED_SHORT") return read_le<uint16_t>(bytes, at);
  if (type == "INT") return read_le<int32_t>(bytes, at);
  if (type == "UNSIGNED_INT") return read_le<uint32_t>(bytes, at);
  if (type == "FLOAT") return read_le<float>(bytes, at);
  return read_le<double>(bytes, at);
}

inline PntsContent read_pnts(const std::string& bytes, const std::string& what) {
  PntsContent out;
  EXPECT_GE(bytes.size(), 28u) << what;
  if (bytes.size() < 28) return out;
  EXPECT_EQ(bytes.substr(0, 4), "pnts") << what;
  EXPECT_EQ(read_le<uint32_t>(bytes, 4), 1u) << what << ": version";
  EXPECT_EQ(read_le<uint32_t>(bytes, 8), bytes.size()) << what << ": byteLength";
  const uint32_t ft_json = read_le<uint32_t>(bytes, 12), ft_bin = read_le<uint32_t>(bytes, 16);
  const uint32_t bt_json = read_le<uint32_t>(bytes, 20), bt_bin = read_le<uint32_t>(bytes, 24);
  EXPECT_EQ(28u + ft_json + ft_bin + bt_json + bt_bin, bytes.size()) << what;
  // Alignment: each JSON ends, and each binary body starts and ends, on 8-byte boundaries.
  EXPECT_EQ((28 + ft_json) % 8, 0u) << what;
  EXPECT_EQ(ft_bin % 8, 0u) << what;
  EXPECT_EQ((28 + ft_json + ft_bin + bt_json) % 8, 0u) << what;
  EXPECT_EQ(bt_bin % 8, 0u) << what;
  out.feature_table = nlohmann::json::parse(bytes.substr(28, ft_json));
  const std::string ft_body = bytes.substr(28 + ft_json, ft_bin);
  const size_t n = out.feature_table.at("POINTS_LENGTH").get<size_t>();
  Eigen::Vector3d rtc = Eigen::Vector3d::Zero();
  if (out.feature_table.contains("RTC_CENTER"))
    for (int a = 0; a < 3; ++a) rtc[a] = out.feature_table["RTC_CENTER"][a].get<double>();
  out.positions.resize(n);
  if (out.feature_table.contains("POSITION")) {
    const size_t offset = out.feature_table["POSITION"]["byteOffset"].get<size_t>();
    EXPECT_EQ(offset % 4, 0u) << what;
    EXPECT_LE(offset + 12 * n, ft_body.size()) << what;
    for (size_t k = 0; k < n && offset + 12 * n <= ft_body.size(); ++k)
      for (int a = 0; a < 3; ++a)
        out.positions[k][a] = rtc[a] + read_le<float>(ft_body, offset + 12 * k + 4 * a);
  } else {
    const nlohmann::json& ft = out.feature_table;
    EXPECT_TRUE(ft.contains("POSITION_QUANTIZED") && ft.contains("QUANTIZED_VOLUME_OFFSET") &&
                ft.contains("QUANTIZED_VOLUME_SCALE"))
        << what << ": no positions";
    const size_t offset = ft["POSITION_QUANTIZED"]["byteOffset"].get<size_t>();
    EXPECT_EQ(offset % 2, 0u) << what;
    EXPECT_LE(offset + 6 * n, ft_body.size()) << what;
    for (size_t k = 0; k < n && offset + 6 * n <= ft_body.size(); ++k)
      for (int a = 0; a < 3; ++a)
        out.positions[k][a] = rtc[a] + ft["QUANTIZED_VOLUME_OFFSET"][a].get<double>() +
                              read_le<uint16_t>(ft_body, offset + 6 * k + 2 * a) / 65535.0 *
                                  ft["QUANTIZED_VOLUME_SCALE"][a].get<double>();
  }
  if (bt_json == 0) return out;
  out.batch_table = nlohmann::json::parse(bytes.substr(28 + ft_json + ft_bin, bt_json));
  const std::string bt_body = bytes.substr(28 + ft_json + ft_bin + bt_json, bt_bin);
  for (const auto& [name, property] : out.batch_table.items()) {
    EXPECT_EQ(property.at("type").get<std::string>(), "SCALAR") << what << ": " << name;
    const std::string type = property.at("componentType").get<std::string>();
    const size_t size = component_bytes(type);
    const size_t offset = property.at("byteOffset").get<size_t>();
    EXPECT_EQ(offset % size, 0u) << what << ": " << name << " misaligned";
    EXPECT_LE(offset + size * n, bt_body.size()) << what << ": " << name;
    if (offset + size * n > bt_body.size()) continue;
    auto& values = out.properties[name];
    for (size_t k = 0; k < n; ++k) values.push_back(component_at(bt_body, offset + size * k, type));
  }
  return out;
}

// A tileset tar extracted by GNU tar (the reference tool) and read tile by tile from
// tileset.json down; the box, error and children of every tile, and its content.
struct TilesetTile {
  std::string uri;
  std::vector<std::string> children;  // uris
  std::vector<double> box;            // 12 numbers
  double geometric_error = 0.0;
  PntsContent content;
};

struct Tileset {
  nlohmann::json json;
  std::map<std::string, TilesetTile> tiles;  // by content uri
  std::string root;
};

inline std::string read_file_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

inline void read_tile(const std::filesystem::path& dir, const nlohmann::json& tile, Tileset& out,
                      std::string* uri_out) {
  TilesetTile t;
  t.uri = tile.at("content").at("uri").get<std::string>();
  t.box = tile.at("boundingVolume").at("box").get<std::vector<double>>();
  EXPECT_EQ(t.box.size(), 12u);
  t.geometric_error = tile.at("geometricError").get<double>();
  t.content = read_pnts(read_file_bytes(dir / t.uri), t.uri);
  if (tile.contains("children"))
    for (const auto& child : tile["children"]) {
      std::string child_uri;
      read_tile(dir, child, out, &child_uri);
      t.children.push_back(child_uri);
    }
  EXPECT_FALSE(out.tiles.count(t.uri)) << t.uri << " twice";
  *uri_out = t.uri;
  out.tiles[t.uri] = std::move(t);
}

inline Tileset read_tileset_tar(const std::filesystem::path& tar,
                                const std::filesystem::path& dir) {
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string command = "tar -xf '" + tar.string() + "' -C '" + dir.string() + "'";
  EXPECT_EQ(std::system(command.c_str()), 0) << command;
  Tileset out;
  out.json = nlohmann::json::parse(read_file_bytes(dir / "tileset.json"));
  EXPECT_EQ(out.json["asset"]["version"], "1.0");
  read_tile(dir, out.json.at("root"), out, &out.root);
  return out;
}

}  // namespace keel::testing
