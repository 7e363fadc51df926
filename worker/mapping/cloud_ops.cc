#include "worker/mapping/cloud_ops.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace keel::mapping {
namespace {

template <typename T>
void compact(std::vector<T>& values, const std::vector<uint8_t>& keep) {
  if (values.empty()) return;
  size_t out = 0;
  for (size_t k = 0; k < values.size(); ++k) {
    if (keep[k]) values[out++] = values[k];
  }
  values.resize(out);
}

template <typename T>
void append_field(std::vector<T>& dst, const std::vector<T>& src, bool dst_was_empty) {
  if (dst_was_empty) {
    dst = src;
  } else if (!dst.empty() && !src.empty()) {
    dst.insert(dst.end(), src.begin(), src.end());
  } else {
    dst.clear();  // one side lacks the field: the merged cloud cannot carry it
  }
}

}  // namespace

void check_field_sizes(const PointCloud& cloud, const char* what) {
  const size_t n = cloud.xyz.size();
  auto check = [&](size_t size, const char* field) {
    if (size != 0 && size != n) {
      throw std::invalid_argument(std::string(what) + ": field '" + field + "' has " +
                                  std::to_string(size) + " values for " + std::to_string(n) +
                                  " points");
    }
  };
  check(cloud.intensity.size(), "intensity");
  check(cloud.ring.size(), "ring");
  check(cloud.time_s.size(), "time");
}

size_t keep_points(PointCloud& cloud, const std::vector<uint8_t>& keep) {
  const size_t before = cloud.xyz.size();
  compact(cloud.xyz, keep);
  compact(cloud.intensity, keep);
  compact(cloud.ring, keep);
  compact(cloud.time_s, keep);
  return before - cloud.xyz.size();
}

size_t remove_non_finite(PointCloud& cloud) {
  std::vector<uint8_t> keep(cloud.size(), 1);
  bool any = false;
  for (size_t k = 0; k < cloud.size(); ++k) {
    if (!cloud.xyz[k].allFinite()) {
      keep[k] = 0;
      any = true;
    }
  }
  return any ? keep_points(cloud, keep) : 0;
}

void transform_points(PointCloud& cloud, const Pose3& T) {
  const Eigen::Matrix3d R = T.linear();
  const Eigen::Vector3d t = T.translation();
  for (Eigen::Vector3f& p : cloud.xyz) p = (R * p.cast<double>() + t).cast<float>();
}

void append_points(PointCloud& dst, const PointCloud& src) {
  if (src.xyz.empty()) return;
  const bool dst_was_empty = dst.xyz.empty();
  dst.xyz.insert(dst.xyz.end(), src.xyz.begin(), src.xyz.end());
  append_field(dst.intensity, src.intensity, dst_was_empty);
  append_field(dst.ring, src.ring, dst_was_empty);
  append_field(dst.time_s, src.time_s, dst_was_empty);
}

}  // namespace keel::mapping
