#include "worker/io/draco/draco_header_check.h"

#include <draco/compression/config/compression_shared.h>
#include <draco/compression/point_cloud/point_cloud_decoder.h>
#include <draco/core/decoder_buffer.h>
#include <draco/core/varint_decoding.h>
#include <draco/metadata/geometry_metadata.h>
#include <draco/metadata/metadata_decoder.h>

#include <stdexcept>

namespace keel::io {
namespace {

// Draco's encoder methods (compression_shared.h): sequential is 0 for both geometries,
// kd-tree (point clouds) and edgebreaker (meshes) are 1.
constexpr uint8_t kSequential = draco::MESH_SEQUENTIAL_ENCODING;
constexpr uint8_t kEdgebreaker = draco::MESH_EDGEBREAKER_ENCODING;
constexpr uint16_t kMetadataFlag = METADATA_FLAG_MASK;  // a macro in Draco

// A count as Draco writes it: a varint from bitstream `varint_since` on, a uint32 before.
std::optional<uint64_t> read_count(draco::DecoderBuffer* buffer, uint16_t varint_since) {
  uint32_t value = 0;
  const bool ok = buffer->bitstream_version() >= varint_since ? draco::DecodeVarint(&value, buffer)
                                                              : buffer->Decode(&value);
  if (!ok) return std::nullopt;
  return value;
}

// PointCloudSequentialDecoder / PointCloudKdTreeDecoder::DecodeGeometryData: an int32.
std::optional<DracoDeclaredCounts> cloud_counts(draco::DecoderBuffer* buffer) {
  int32_t points = 0;
  if (!buffer->Decode(&points) || points < 0) return std::nullopt;
  DracoDeclaredCounts counts;
  counts.points = static_cast<uint64_t>(points);
  return counts;
}

// MeshSequentialDecoder::DecodeConnectivity: faces then points (varints since 2.2).
std::optional<DracoDeclaredCounts> sequential_mesh_counts(draco::DecoderBuffer* buffer) {
  const uint16_t since = DRACO_BITSTREAM_VERSION(2, 2);
  const auto faces = read_count(buffer, since);
  const auto points = faces ? read_count(buffer, since) : std::nullopt;
  if (!points) return std::nullopt;
  return DracoDeclaredCounts{true, *points, 0, *faces};
}

// MeshEdgebreakerDecoder::InitializeDecoder (the traversal type, a byte), then
// MeshEdgeBreakerDecoderImpl::DecodeConnectivity: [new vertices before 2.2], encoded
// vertices, faces, attribute data (a byte), symbols, split symbols (varints since 2.0). The
// corner table is sized at the faces and at the encoded vertices plus the split symbols.
std::optional<DracoDeclaredCounts> edgebreaker_counts(draco::DecoderBuffer* buffer) {
  const uint16_t since = DRACO_BITSTREAM_VERSION(2, 0);
  uint8_t byte = 0;
  if (!buffer->Decode(&byte)) return std::nullopt;  // traversal decoder type
  if (buffer->bitstream_version() < DRACO_BITSTREAM_VERSION(2, 2) && !read_count(buffer, since))
    return std::nullopt;  // new vertices
  const auto vertices = read_count(buffer, since);
  const auto faces = vertices ? read_count(buffer, since) : std::nullopt;
  if (!faces || !buffer->Decode(&byte)) return std::nullopt;  // attribute data
  const auto symbols = read_count(buffer, since);
  const auto splits = symbols ? read_count(buffer, since) : std::nullopt;
  if (!splits) return std::nullopt;
  return DracoDeclaredCounts{true, *vertices, *splits, *faces};
}

}  // namespace

std::optional<DracoDeclaredCounts> read_draco_counts(const std::string& bytes) {
  draco::DecoderBuffer buffer;
  buffer.Init(bytes.data(), bytes.size());
  draco::DracoHeader header;
  if (!draco::PointCloudDecoder::DecodeHeader(&buffer, &header).ok()) return std::nullopt;
  if (header.version_major < 1 || header.version_major > 2) return std::nullopt;
  buffer.set_bitstream_version(DRACO_BITSTREAM_VERSION(header.version_major, header.version_minor));
  if (buffer.bitstream_version() >= DRACO_BITSTREAM_VERSION(1, 3) &&
      (header.flags & kMetadataFlag)) {
    draco::GeometryMetadata metadata;
    if (!draco::MetadataDecoder().DecodeGeometryMetadata(&buffer, &metadata)) return std::nullopt;
  }
  if (header.encoder_type == draco::POINT_CLOUD) return cloud_counts(&buffer);
  if (header.encoder_type != draco::TRIANGULAR_MESH) return std::nullopt;
  if (header.encoder_method == kSequential) return sequential_mesh_counts(&buffer);
  if (header.encoder_method == kEdgebreaker) return edgebreaker_counts(&buffer);
  return std::nullopt;
}

void check_draco_header(const std::string& bytes, const std::string& what,
                        const DracoLimits& limits) {
  draco::DecoderBuffer buffer;
  buffer.Init(bytes.data(), bytes.size());
  draco::DracoHeader header;
  if (!draco::PointCloudDecoder::DecodeHeader(&buffer, &header).ok()) return;  // Draco says so
  const bool mesh = header.encoder_type == draco::TRIANGULAR_MESH;
  const int major =
      mesh ? draco::kDracoMeshBitstreamVersionMajor : draco::kDracoPointCloudBitstreamVersionMajor;
  const int minor =
      mesh ? draco::kDracoMeshBitstreamVersionMinor : draco::kDracoPointCloudBitstreamVersionMinor;
  if (header.version_major != major || header.version_minor != minor) {
    throw std::runtime_error(what + ": Draco bitstream " + std::to_string(header.version_major) +
                             "." + std::to_string(header.version_minor) + "; Keel reads " +
                             (mesh ? "meshes" : "point clouds") + " of bitstream " +
                             std::to_string(major) + "." + std::to_string(minor) +
                             " (re-encode with a current draco_encoder)");
  }
  const auto counts = read_draco_counts(bytes);
  if (!counts) return;
  const auto refuse = [&](uint64_t n, const char* items, uint64_t limit) {
    throw std::runtime_error(what + ": the Draco header declares " + std::to_string(n) + " " +
                             items + ", more than Keel decodes (at most " + std::to_string(limit) +
                             "); the file is corrupt or not Keel's");
  };
  const uint64_t points = counts->points + counts->split_vertices;
  if (points > limits.max_points)
    refuse(points, counts->mesh ? "vertices" : "points", limits.max_points);
  if (counts->faces > limits.max_faces) refuse(counts->faces, "faces", limits.max_faces);
}

}  // namespace keel::io
