// A scan or map as structure-of-arrays: positions always, the other fields when present.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

#include "core/time.h"

namespace keel {

struct PointCloud {
  std::vector<Eigen::Vector3f> xyz;  // in `frame`
  std::vector<float> intensity;      // empty or xyz.size()
  std::vector<uint16_t> ring;        // empty or xyz.size()
  std::vector<float> time_s;         // per-point time offset from t_ns (s); empty or xyz.size()
  TimeNs t_ns = 0;                   // scan stamp (sweep start)
  std::string frame;                 // sensor name or "world"

  size_t size() const { return xyz.size(); }
  bool empty() const { return xyz.empty(); }
  bool has_intensity() const { return !intensity.empty(); }
  bool has_ring() const { return !ring.empty(); }
  bool has_time() const { return !time_s.empty(); }
  void reserve(size_t n) {
    xyz.reserve(n);
  }
};

}  // namespace keel
