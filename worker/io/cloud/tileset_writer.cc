#include "worker/io/cloud/tileset_writer.h"

#include <archive.h>
#include <archive_entry.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

namespace keel::io {
namespace {

using nlohmann::json;

template <typename T>
void put(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));  // little endian, as the format and Keel's hosts are
  out.append(bytes, sizeof(T));
}

void pad_to_8(std::string& body, char fill) {
  while (body.size() % 8 != 0) body.push_back(fill);
}

// A JSON header padded with spaces so that `start` + its length is a multiple of 8 (3D Tiles:
// the binary body that follows starts on an 8-byte boundary).
std::string padded_json(const json& header, size_t start) {
  std::string text = header.dump();
  while ((start + text.size()) % 8 != 0) text.push_back(' ');
  return text;
}

const char* component_type(PntsAttribute::Type type) {
  return type == PntsAttribute::Type::kFloat ? "FLOAT" : "UNSIGNED_BYTE";
}

}  // namespace

std::string encode_pnts(const std::vector<Eigen::Vector3f>& xyz, const Eigen::Vector3d& cube_min,
                        double cube_edge_m, const std::vector<PntsAttribute>& attributes,
                        const std::vector<std::vector<float>>& values) {
  const size_t n = xyz.size();
  if (values.size() != attributes.size())
    throw std::invalid_argument("pnts: " + std::to_string(values.size()) + " value arrays for " +
                                std::to_string(attributes.size()) + " attributes");
  if (!(cube_edge_m > 0.0) || !std::isfinite(cube_edge_m))
    throw std::invalid_argument("pnts: cube edge must be positive, got " +
                                std::to_string(cube_edge_m));
  constexpr size_t kHeaderBytes = 28;

  // Feature table: quantized positions over the cube.
  std::string feature_binary;
  feature_binary.reserve(6 * n + 8);
  const double scale = 65535.0 / cube_edge_m;
  for (const Eigen::Vector3f& p : xyz)
    for (int axis = 0; axis < 3; ++axis) {
      const double q = std::round((static_cast<double>(p[axis]) - cube_min[axis]) * scale);
      put(feature_binary, static_cast<uint16_t>(std::clamp(q, 0.0, 65535.0)));
    }
  pad_to_8(feature_binary, '\0');
  const json feature_header = {
      {"POINTS_LENGTH", n},
      {"POSITION_QUANTIZED", {{"byteOffset", 0}}},
      {"QUANTIZED_VOLUME_OFFSET", {cube_min.x(), cube_min.y(), cube_min.z()}},
      {"QUANTIZED_VOLUME_SCALE", {cube_edge_m, cube_edge_m, cube_edge_m}}};
  const std::string feature_json = padded_json(feature_header, kHeaderBytes);

  // Batch table: one binary property per attribute, each starting on an 8-byte boundary.
  std::string batch_binary;
  json batch_header = json::object();
  for (size_t a = 0; a < attributes.size(); ++a) {
    if (values[a].size() != n)
      throw std::invalid_argument("pnts: attribute '" + attributes[a].name + "' has " +
                                  std::to_string(values[a].size()) + " values for " +
                                  std::to_string(n) + " points");
    batch_header[attributes[a].name] = {{"byteOffset", batch_binary.size()},
                                        {"componentType", component_type(attributes[a].type)},
                                        {"type", "SCALAR"}};
    for (const float v : values[a]) {
      if (attributes[a].type == PntsAttribute::Type::kFloat) {
        put(batch_binary, v);
      } else {
        if (!(v >= 0.f && v <= 255.f) || v != std::floor(v))
          throw std::invalid_argument("pnts: attribute '" + attributes[a].name + "' value " +
                                      std::to_string(v) + " is not a byte");
        put(batch_binary, static_cast<uint8_t>(v));
      }
    }
    pad_to_8(batch_binary, '\0');
  }
  const size_t batch_start = kHeaderBytes + feature_json.size() + feature_binary.size();
  const std::string batch_json = attributes.empty() ? "" : padded_json(batch_header, batch_start);

  std::string out;
  const size_t total = batch_start + batch_json.size() + batch_binary.size();
  if (total > std::numeric_limits<uint32_t>::max())
    throw std::invalid_argument("pnts: a tile of " + std::to_string(n) + " points exceeds 4 GiB");
  out.reserve(total);
  out.append("pnts", 4);
  put(out, uint32_t{1});
  put(out, static_cast<uint32_t>(total));
  put(out, static_cast<uint32_t>(feature_json.size()));
  put(out, static_cast<uint32_t>(feature_binary.size()));
  put(out, static_cast<uint32_t>(batch_json.size()));
  put(out, static_cast<uint32_t>(batch_binary.size()));
  out += feature_json;
  out += feature_binary;
  out += batch_json;
  out += batch_binary;
  return out;
}

struct TilesetTarWriter::Archive {
  struct archive* handle = nullptr;
  ~Archive() {
    if (handle) archive_write_free(handle);
  }
};

TilesetTarWriter::TilesetTarWriter(std::filesystem::path tar_path,
                                   std::vector<PntsAttribute> attributes, json extras)
    : path_(std::move(tar_path)),
      temp_path_(path_.string() + ".partial"),
      attributes_(std::move(attributes)),
      extras_(std::move(extras)),
      archive_(std::make_unique<Archive>()),
      min_(attributes_.size(), std::numeric_limits<double>::infinity()),
      max_(attributes_.size(), -std::numeric_limits<double>::infinity()) {
  archive_->handle = archive_write_new();
  if (!archive_->handle || archive_write_set_format_ustar(archive_->handle) != ARCHIVE_OK ||
      archive_write_open_filename(archive_->handle, temp_path_.c_str()) != ARCHIVE_OK)
    throw std::runtime_error(
        "tileset " + path_.string() + ": cannot write: " +
        (archive_->handle ? archive_error_string(archive_->handle) : "out of memory"));
}

TilesetTarWriter::~TilesetTarWriter() {
  if (finished_) return;
  archive_.reset();
  std::error_code ignored;
  std::filesystem::remove(temp_path_, ignored);
}

void TilesetTarWriter::add_member(const std::string& name, const std::string& bytes) {
  std::unique_ptr<archive_entry, decltype(&archive_entry_free)> entry(archive_entry_new(),
                                                                      archive_entry_free);
  archive_entry_set_pathname(entry.get(), name.c_str());
  archive_entry_set_size(entry.get(), static_cast<la_int64_t>(bytes.size()));
  archive_entry_set_filetype(entry.get(), AE_IFREG);
  archive_entry_set_perm(entry.get(), 0644);
  archive_entry_set_mtime(entry.get(), 0, 0);  // same tiles, same bytes, same artifact
  if (archive_write_header(archive_->handle, entry.get()) != ARCHIVE_OK ||
      archive_write_data(archive_->handle, bytes.data(), bytes.size()) !=
          static_cast<la_ssize_t>(bytes.size()))
    throw std::runtime_error("tileset " + path_.string() + ": writing " + name + ": " +
                             archive_error_string(archive_->handle));
  bytes_ += bytes.size();
}

void TilesetTarWriter::add_tile(const std::string& name, const Eigen::Vector3d& cube_min,
                                double cube_edge_m, double geometric_error_m,
                                const std::vector<int>& children,
                                const std::vector<Eigen::Vector3f>& xyz,
                                const std::vector<std::vector<float>>& values) {
  if (finished_) throw std::logic_error("tileset: add_tile after finish");
  for (const int c : children)
    if (!nodes_.count(name + std::to_string(c)))
      throw std::invalid_argument("tileset: tile " + name + " names child " + std::to_string(c) +
                                  ", which was not added before it");
  add_member(name + ".pnts", encode_pnts(xyz, cube_min, cube_edge_m, attributes_, values));
  nodes_[name] = Node{cube_min, cube_edge_m, geometric_error_m, children};
  if (!children.empty()) return;
  points_ += xyz.size();
  for (size_t a = 0; a < attributes_.size(); ++a)
    for (const float v : values[a]) {
      if (std::isnan(v)) continue;
      min_[a] = std::min(min_[a], static_cast<double>(v));
      max_[a] = std::max(max_[a], static_cast<double>(v));
    }
}

json TilesetTarWriter::tile_json(const std::string& name) const {
  const Node& node = nodes_.at(name);
  const double h = node.edge_m / 2;
  const Eigen::Vector3d c = node.cube_min + Eigen::Vector3d::Constant(h);
  json tile = {{"boundingVolume", {{"box", {c.x(), c.y(), c.z(), h, 0, 0, 0, h, 0, 0, 0, h}}}},
               {"geometricError", node.geometric_error_m},
               {"content", {{"uri", name + ".pnts"}}}};
  if (!node.children.empty()) {
    tile["children"] = json::array();
    for (const int c : node.children)
      tile["children"].push_back(tile_json(name + std::to_string(c)));
  }
  return tile;
}

json TilesetTarWriter::finish(const std::string& root) {
  if (finished_) throw std::logic_error("tileset: finish twice");
  if (!nodes_.count(root)) throw std::invalid_argument("tileset: no root tile " + root);
  json tileset = {{"asset", {{"version", "1.0"}, {"generator", "keel"}}}};
  const Node& root_node = nodes_.at(root);
  tileset["geometricError"] =
      root_node.geometric_error_m > 0.0 ? 2 * root_node.geometric_error_m : root_node.edge_m;
  json properties = json::object();
  json ranges = json::object();
  for (size_t a = 0; a < attributes_.size(); ++a) {
    if (!(min_[a] <= max_[a])) continue;  // no defined value
    properties[attributes_[a].name] = {{"minimum", min_[a]}, {"maximum", max_[a]}};
    ranges[attributes_[a].name] = {{"min", min_[a]}, {"max", max_[a]}};
  }
  tileset["properties"] = properties;
  json keel = extras_.is_object() ? extras_ : json::object();
  keel["points"] = points_;
  keel["tiles"] = nodes_.size();
  keel["attributes"] = ranges;
  tileset["extras"] = {{"keel", keel}};
  tileset["root"] = tile_json(root);
  tileset["root"]["refine"] = "REPLACE";
  add_member("tileset.json", tileset.dump());
  if (archive_write_close(archive_->handle) != ARCHIVE_OK)
    throw std::runtime_error("tileset " + path_.string() + ": " +
                             archive_error_string(archive_->handle));
  archive_.reset();
  std::filesystem::rename(temp_path_, path_);
  finished_ = true;
  return tileset;
}

}  // namespace keel::io
