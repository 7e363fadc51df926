// OGC 3D Tiles 1.0 point-cloud tilesets (issue 17): `.pnts` tiles (3D Tiles 1.0 "Point Cloud"
// format, which 3D Tiles 1.1 still accepts) and a `tileset.json` over them, written tile by
// tile into one uncompressed POSIX tar (libarchive), the folder artifact the server serves
// member by member. docs/artifacts.md describes the layout a viewer relies on.
#pragma once

#include <nlohmann/json.hpp>

#include <Eigen/Core>

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace keel::io {

// A per-point batch-table property, stored as FLOAT or UNSIGNED_BYTE (the values are given as
// floats; UNSIGNED_BYTE ones must be whole numbers in [0, 255]).
struct PntsAttribute {
  enum class Type { kFloat, kUnsignedByte };
  std::string name;
  Type type = Type::kFloat;
};

// One .pnts file: POINTS_LENGTH, POSITION_QUANTIZED (uint16 x 3) over the cube
// (QUANTIZED_VOLUME_OFFSET = cube_min, QUANTIZED_VOLUME_SCALE = its edge, each coordinate
// round((p - min) / edge * 65535) clamped to [0, 65535]), and the attributes as batch-table
// binary properties; the JSON headers and binary bodies padded to 8 bytes as the specification
// requires. Throws std::invalid_argument for attributes of the wrong size or bad byte values.
std::string encode_pnts(const std::vector<Eigen::Vector3f>& xyz, const Eigen::Vector3d& cube_min,
                        double cube_edge_m, const std::vector<PntsAttribute>& attributes,
                        const std::vector<std::vector<float>>& values);

class TilesetTarWriter {
 public:
  // Writes to a temporary sibling of `tar_path`, renamed into place by finish(). `extras` goes
  // to tileset.json's extras.keel, with "points", "tiles" and each attribute's "min"/"max"
  // added. Throws std::runtime_error naming the file when it cannot be written.
  TilesetTarWriter(std::filesystem::path tar_path, std::vector<PntsAttribute> attributes,
                   nlohmann::json extras);
  ~TilesetTarWriter();  // removes the temporary file unless finished
  TilesetTarWriter(const TilesetTarWriter&) = delete;
  TilesetTarWriter& operator=(const TilesetTarWriter&) = delete;

  // Adds tile `name` (member `<name>.pnts`), children before their parent (its `children` must
  // have been added, as `<name><index>`). A tile without children is a finest tile: its points
  // count in the map's points and attribute ranges. Not thread-safe.
  void add_tile(const std::string& name, const Eigen::Vector3d& cube_min, double cube_edge_m,
                double geometric_error_m, const std::vector<int>& children,
                const std::vector<Eigen::Vector3f>& xyz,
                const std::vector<std::vector<float>>& values);
  // Writes tileset.json with `root` as the root tile, closes the tar and moves it into place.
  // Returns tileset.json.
  nlohmann::json finish(const std::string& root);

  size_t tiles() const { return nodes_.size(); }
  uint64_t points() const { return points_; }
  uint64_t bytes() const { return bytes_; }

 private:
  struct Node {
    Eigen::Vector3d cube_min;
    double edge_m = 0.0;
    double geometric_error_m = 0.0;
    std::vector<int> children;
  };
  void add_member(const std::string& name, const std::string& bytes);
  nlohmann::json tile_json(const std::string& name) const;

  std::filesystem::path path_, temp_path_;
  std::vector<PntsAttribute> attributes_;
  nlohmann::json extras_;
  struct Archive;
  std::unique_ptr<Archive> archive_;
  std::map<std::string, Node> nodes_;
  std::vector<double> min_, max_;
  uint64_t points_ = 0, bytes_ = 0;
  bool finished_ = false;
};

}  // namespace keel::io
