#include "worker/io/draco/draco_position_error.h"

#include <draco/point_cloud/point_cloud.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <unordered_map>

namespace keel::io {
namespace {

// Largest distance from each original point to the decoded point it became. Quantization
// rounds each coordinate to the nearest grid value, so a point's own decoded point is the
// nearest of all decoded points (they all sit on that grid): the nearest-neighbour distance
// is exactly the per-point error, with no need for Draco's (reordered) point ids. A hash
// grid of cell `step` finds it among the 27 cells around the original.
template <typename Vector>
double max_nearest_distance(const std::vector<Vector>& originals, const std::vector<bool>* used,
                            const std::vector<Eigen::Vector3f>& decoded, double step,
                            double tolerance) {
  struct CellHash {
    size_t operator()(const Eigen::Vector3i& c) const {
      return (static_cast<size_t>(c.x()) * 73856093u) ^ (static_cast<size_t>(c.y()) * 19349663u) ^
             (static_cast<size_t>(c.z()) * 83492791u);
    }
  };
  struct CellEqual {
    bool operator()(const Eigen::Vector3i& a, const Eigen::Vector3i& b) const { return a == b; }
  };
  Eigen::Vector3d origin = decoded[0].cast<double>();
  for (const auto& p : decoded) origin = origin.cwiseMin(p.cast<double>());
  // Cells centred on the grid nodes (round, not floor): a decoded point is alone in its cell,
  // and an original's own node is in the cell it rounds to, so one lookup usually suffices.
  auto cell_of = [&](const Eigen::Vector3d& p) -> Eigen::Vector3i {
    return ((p - origin) / step).array().round().cast<int>();
  };
  std::unordered_map<Eigen::Vector3i, std::vector<Eigen::Vector3d>, CellHash, CellEqual> grid;
  for (const auto& p : decoded) {
    auto& bucket = grid[cell_of(p.cast<double>())];
    // Duplicates of one grid point add nothing to a nearest-point search.
    if (std::find(bucket.begin(), bucket.end(), p.cast<double>()) == bucket.end()) {
      bucket.push_back(p.cast<double>());
    }
  }
  double max_error = 0.0;
  for (size_t i = 0; i < originals.size(); ++i) {
    if (used != nullptr && !(*used)[i]) continue;
    const Eigen::Vector3d p = originals[i].template cast<double>();
    const Eigen::Vector3i cell = cell_of(p);
    double best = std::numeric_limits<double>::infinity();
    if (const auto own = grid.find(cell); own != grid.end()) {
      for (const auto& q : own->second) best = std::min(best, (q - p).norm());
    }
    for (int dx = -1; dx <= 1 && !(best <= tolerance); ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = grid.find(cell + Eigen::Vector3i(dx, dy, dz));
          if (it == grid.end()) continue;
          for (const auto& q : it->second) best = std::min(best, (q - p).norm());
        }
      }
    }
    if (best > tolerance) {
      throw std::runtime_error("draco round trip: point " + std::to_string(i) +
                               " has no decoded point within the quantization bound");
    }
    max_error = std::max(max_error, best);
  }
  return max_error;
}

template <typename Vector>
PositionBounds bounds_of(const std::vector<Vector>& positions) {
  PositionBounds bounds;
  for (const Vector& p : positions) bounds.add(p);
  return bounds;
}

}  // namespace

double error_tolerance(const PositionBounds& bounds, const DracoOptions& options,
                       DracoEncoded* result) {
  const float range = (bounds.max - bounds.min).maxCoeff();
  result->position_range_m = range > 0.f ? range : 1.0;
  const double step = result->position_range_m / ((1u << options.position_bits) - 1);
  result->position_error_bound_m = 0.5 * std::sqrt(3.0) * step;
  return result->position_error_bound_m + 8.0 * bounds.largest_abs * 1.2e-7;
}

template <typename Vector>
void measure_error(const std::vector<Vector>& originals, const std::vector<bool>* used,
                   const std::vector<Eigen::Vector3f>& decoded, const DracoOptions& options,
                   DracoEncoded* result) {
  const double tolerance = error_tolerance(bounds_of(originals), options, result);
  const double step = result->position_range_m / ((1u << options.position_bits) - 1);
  result->max_position_error_m = max_nearest_distance(originals, used, decoded, step, tolerance);
  result->error_method = "nearest_decoded";
}

template void measure_error(const std::vector<Eigen::Vector3f>&, const std::vector<bool>*,
                            const std::vector<Eigen::Vector3f>&, const DracoOptions&,
                            DracoEncoded*);
template void measure_error(const std::vector<Eigen::Vector3d>&, const std::vector<bool>*,
                            const std::vector<Eigen::Vector3f>&, const DracoOptions&,
                            DracoEncoded*);

PositionBounds position_bounds(const PositionParts& parts) {
  PositionBounds bounds;
  for (const std::vector<Eigen::Vector3f>* part : parts)
    for (const Eigen::Vector3f& p : *part) bounds.add(p);
  return bounds;
}

namespace {

// The position Draco's decoder returns for each input position, computed with Draco's own
// float arithmetic: AttributeQuantizationTransform::ComputeParameters (per-axis minimum, range
// = largest extent, 1 when all points coincide), Quantizer (q = floor((p - min) *
// (2^bits - 1) / range + 0.5)) and Dequantizer (q * range / (2^bits - 1) + min), as in
// draco/attributes/attribute_quantization_transform.cc and draco/core/quantization_utils.cc.
class DracoPositionReplica {
 public:
  // `min` and `hi`: the per-axis extremes of the input positions.
  DracoPositionReplica(const Eigen::Vector3f& min, const Eigen::Vector3f& hi, int bits)
      : min_(min) {
    float range = 0.f;
    for (int c = 0; c < 3; ++c) range = std::max(range, hi[c] - min_[c]);
    if (range == 0.f) range = 1.f;
    const auto max_quantized = static_cast<int32_t>((1u << bits) - 1);
    inverse_delta_ = static_cast<float>(max_quantized) / range;
    delta_ = range / static_cast<float>(max_quantized);
  }
  Eigen::Vector3f decoded(const Eigen::Vector3f& p) const {
    Eigen::Vector3f out;
    for (int c = 0; c < 3; ++c) {
      float value = p[c] - min_[c];
      value *= inverse_delta_;
      const auto q = static_cast<int32_t>(std::floor(value + 0.5f));
      float back = static_cast<float>(q) * delta_;
      back = back + min_[c];
      out[c] = back;
    }
    return out;
  }

 private:
  Eigen::Vector3f min_;
  float inverse_delta_ = 1.f, delta_ = 1.f;
};

// Order-independent digest of a multiset of float triples: two sums (mod 2^64) of independent
// 64-bit mixes of the bit patterns. Equal multisets give equal digests; unequal ones collide
// with probability ~2^-128.
class MultisetDigest {
 public:
  void add(const Eigen::Vector3f& p) {
    uint32_t bits[3];
    for (int c = 0; c < 3; ++c) {
      const float value = p[c] + 0.0f;  // -0 and +0 are the same position
      std::memcpy(&bits[c], &value, sizeof(float));
    }
    const uint64_t xy = (static_cast<uint64_t>(bits[0]) << 32) | bits[1];
    sum_a_ += mix(xy ^ mix(bits[2] + 0x9e3779b97f4a7c15ULL));
    sum_b_ += mix(mix(xy + 0xd1b54a32d192ed03ULL) ^ (bits[2] * 0xc2b2ae3d27d4eb4fULL));
    ++count_;
  }
  bool operator==(const MultisetDigest& other) const {
    return sum_a_ == other.sum_a_ && sum_b_ == other.sum_b_ && count_ == other.count_;
  }

 private:
  static uint64_t mix(uint64_t x) {  // splitmix64 finalizer
    x ^= x >> 30;
    x *= 0xbf58476d1ce4e5b9ULL;
    x ^= x >> 27;
    x *= 0x94d049bb133111ebULL;
    x ^= x >> 31;
    return x;
  }
  uint64_t sum_a_ = 0, sum_b_ = 0, count_ = 0;
};
}  // namespace

// The point cloud's error without a spatial search: each input position's decoded value is
// predicted by DracoPositionReplica, and the prediction is accepted only when the multiset of
// predicted positions equals the multiset Draco actually decoded (MultisetDigest). Then every
// decoded point is exactly the quantization of an input point, and the largest |predicted -
// original| is the largest error. O(n) time, O(1) memory. Returns false (nothing measured)
// when the decoded points differ from the prediction.
bool measure_error_by_replica(const PositionParts& originals, const PositionBounds& bounds,
                              const draco::PointCloud& decoded, const DracoOptions& options,
                              double tolerance, DracoEncoded* result) {
  const draco::PointAttribute* position =
      decoded.GetNamedAttribute(draco::GeometryAttribute::POSITION);
  if (position == nullptr || position->num_components() != 3) return false;
  MultisetDigest actual;
  if (position->data_type() == draco::DT_FLOAT32 && position->is_mapping_identity() &&
      position->byte_stride() == 3 * sizeof(float)) {
    // The decoder's float buffer, read directly (ConvertValue per point costs ~4x more).
    const uint8_t* data = position->GetAddress(draco::AttributeValueIndex(0));
    for (uint32_t i = 0; i < decoded.num_points(); ++i) {
      Eigen::Vector3f p;
      std::memcpy(p.data(), data + 3 * sizeof(float) * i, 3 * sizeof(float));
      actual.add(p);
    }
  } else {
    for (draco::PointIndex i(0); i < decoded.num_points(); ++i) {
      Eigen::Vector3f p = Eigen::Vector3f::Zero();  // kept when a value does not convert
      position->ConvertValue<float>(position->mapped_index(i), 3, p.data());
      actual.add(p);
    }
  }
  const DracoPositionReplica replica(bounds.min, bounds.max, options.position_bits);
  MultisetDigest predicted;
  double max_squared = 0.0;
  for (const std::vector<Eigen::Vector3f>* part : originals) {
    for (const Eigen::Vector3f& p : *part) {
      const Eigen::Vector3f d = replica.decoded(p);
      predicted.add(d);
      max_squared = std::max(max_squared, (d.cast<double>() - p.cast<double>()).squaredNorm());
    }
  }
  if (!(predicted == actual)) return false;
  const double max_error = std::sqrt(max_squared);
  if (max_error > tolerance) {
    throw std::runtime_error("draco round trip: a point moved " + std::to_string(max_error) +
                             " m, more than the quantization bound " + std::to_string(tolerance) +
                             " m");
  }
  result->max_position_error_m = max_error;
  result->error_method = "replica";
  return true;
}

}  // namespace keel::io
