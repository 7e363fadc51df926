// Point records packed field by field (PCD, binary PLY, sensor_msgs/PointCloud2 all look like
// this) and their unpacking into keel::PointCloud. One place converts the per-point time field
// (Velodyne float s, Ouster uint32 ns, absolute stamps) into float seconds from the scan
// stamp, and checks that the values fit the declared unit and reference.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/point_cloud.h"
#include "proto/mission_manifest.h"

namespace keel::io {

namespace lidar {
struct VelodyneCalibration;
}

enum class FieldType {
  kInt8,
  kUint8,
  kInt16,
  kUint16,
  kInt32,
  kUint32,
  kInt64,
  kUint64,
  kFloat32,
  kFloat64
};

size_t field_size(FieldType type);
bool is_integer(FieldType type);
std::string to_string(FieldType type);

struct PackedField {
  std::string name;
  FieldType type = FieldType::kFloat32;
  size_t offset = 0;  // bytes from the start of a point record
  size_t count = 1;   // elements (only the first is read)
  // Bytes from one point's value to the next: 0 for point records (the view's point_step);
  // a field's own width when the data are stored field by field (PCD binary_compressed), the
  // offset then being where the field's column starts.
  size_t stride = 0;
};

struct PackedCloudView {
  const uint8_t* data = nullptr;
  size_t num_points = 0;
  size_t point_step = 0;  // bytes per point record
  std::vector<PackedField> fields;

  const PackedField* find(const std::string& name) const;
};

struct ScanReadOptions {
  std::optional<proto::PointTimeSpec> point_time;  // none: points share the scan stamp
  // Nominal sweep period (1 / rate_hz). Time offsets beyond 10 periods are an error; 0 = no
  // such check.
  double sweep_period_s = 0.0;
  bool keep_non_finite = false;  // false: drop points with NaN/inf coordinates
  std::string frame;             // copied into PointCloud::frame
  // A topic of raw velodyne_msgs/VelodyneScan packets is decoded with this calibration
  // (lidar/velodyne_scan.h; the firing times replace point_time); null: PointCloud2 only.
  std::shared_ptr<const lidar::VelodyneCalibration> packets;
};

// Unpacks x, y, z (float or double, required), intensity and ring (any numeric, optional) and
// the time field. `source` names the file or bag message in errors. Throws IoError.
PointCloud unpack_cloud(const PackedCloudView& view, TimeNs t_ns, const ScanReadOptions& options,
                        const std::string& source);

// Converts raw per-point times (the field of `view`; with a split spec also its nsec_field,
// combined exactly as sec * 1e9 + nsec in int64 ns) into seconds from `t_ns` per `spec`:
// scan_start offsets are >= 0, scan_end offsets <= 0 (the stamp marks the last point), and
// absolute times have the stamp subtracted in integer ns (float64 epoch seconds keep their
// own ~0.24 us resolution). Fails naming `source`, the field and the values found, and the
// unit or reference they would fit, when they cannot be what the spec declares (non-finite,
// offsets beyond 10 sweep periods, more than a sweep on the wrong side of the stamp, or a
// span that only fits a coarser unit). Exposed for tests.
std::vector<double> point_time_offsets(const PackedCloudView& view, const PackedField& field,
                                       TimeNs t_ns, const proto::PointTimeSpec& spec,
                                       double sweep_period_s, const std::string& source);

}  // namespace keel::io

namespace keel::io {

// Owned packed records: what the writers (PCD, PLY, PointCloud2) serialise.
struct PackedCloud {
  std::vector<PackedField> fields;
  size_t point_step = 0;
  size_t num_points = 0;
  std::vector<uint8_t> data;

  PackedCloudView view() const { return {data.data(), num_points, point_step, fields}; }
};

// How a writer stores the per-point time (ScanWriteOptions).
struct PointTimeEncoding {
  proto::PointTimeSpec spec;             // field name, unit, reference
  FieldType type = FieldType::kFloat32;  // Velodyne float32 s, Ouster uint32 ns, ...
};

// Packs x y z (float32), intensity (float32) and ring (uint16) when present, and the time
// field when `time` is given and the cloud has per-point times: raw = (offset [+ stamp]) /
// unit, rounded for integer types (absolute integer stamps are computed exactly in ns). A
// split spec writes `field` (whole seconds, of `type`) and `nsec_field` (uint32 ns). Offsets
// are written as the cloud holds them, relative to cloud.t_ns: a scan_end cloud's stamp is
// its last point and its offsets are <= 0.
PackedCloud pack_cloud(const PointCloud& cloud, const std::optional<PointTimeEncoding>& time);

}  // namespace keel::io
