// Recognises a PointCloud2's per-point time field from the field names and value ranges that
// real drivers write, for a mission draft's `point_time:`:
//   Velodyne `time` float32 s from the sweep start (or to its end: negative values when the
//   driver stamps the last packet), Ouster `t` uint32 ns from the scan start, Livox / Hesai
//   absolute float64 `timestamp` (epoch s), absolute integer ns/us, and split integer pairs
//   (`time_sec` + `time_nsec`, `sec` + `nsec`, ...), absolute or relative.
// The unit of a relative field is the one whose scaling makes the sweep span closest to the
// topic's sweep period; the reference is scan_end when every offset is <= 0 (the stamp marks
// the last point), scan_start when every offset is >= 0.
#pragma once

#include <optional>
#include <string>

#include "proto/mission_manifest.h"
#include "worker/io/cloud/packed_cloud.h"

namespace keel::init {

struct PointTimeGuess {
  std::optional<proto::PointTimeSpec> spec;  // none: no time field recognised
  std::string evidence;  // what the values were and why this reading: for the draft's comment
  bool certain = false;  // false: the user must confirm (the draft says so)
};

// `sweep_period_s`: 1 / the topic's measured rate (0: unknown, 0.1 s is assumed).
PointTimeGuess guess_point_time(const io::PackedCloudView& view, TimeNs stamp_ns,
                                double sweep_period_s);

}  // namespace keel::init
