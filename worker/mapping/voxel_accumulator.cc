#include "worker/mapping/voxel_accumulator.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace keel::mapping {
namespace {

int64_t axis_index(double coordinate, double inverse_leaf) {
  const double scaled = std::floor(coordinate * inverse_leaf);
  // 2^62: keeps neighbouring-index arithmetic (i + 1) and the hash free of overflow.
  constexpr double kLimit = 4.611686018427388e18;
  if (!(std::abs(scaled) < kLimit)) {
    throw std::invalid_argument("voxel grid: coordinate " + std::to_string(coordinate) +
                                " / leaf does not fit a 62-bit voxel index");
  }
  return static_cast<int64_t>(scaled);
}

}  // namespace

VoxelKey voxel_of(const Eigen::Vector3f& p, double inverse_leaf) {
  return VoxelKey{axis_index(p.x(), inverse_leaf), axis_index(p.y(), inverse_leaf),
                  axis_index(p.z(), inverse_leaf)};
}

VoxelAccumulator::VoxelAccumulator(double leaf_m) : leaf_m_(leaf_m), inverse_leaf_(1.0 / leaf_m) {
  if (!std::isfinite(leaf_m) || leaf_m <= 0.0) {
    throw std::invalid_argument("voxel grid: leaf must be a positive number of metres, got " +
                                std::to_string(leaf_m));
  }
}

VoxelAccumulator::~VoxelAccumulator() = default;
VoxelAccumulator::VoxelAccumulator(VoxelAccumulator&&) noexcept = default;
VoxelAccumulator& VoxelAccumulator::operator=(VoxelAccumulator&&) noexcept = default;

void VoxelAccumulator::grow() {
  const size_t capacity = std::max<size_t>(1024, slots_.size() * 2);
  std::vector<Slot> slots(capacity);
  const size_t mask = capacity - 1;
  for (size_t index = 0; index < size_; ++index) {
    size_t s = voxel_hash(entry(index).key) & mask;
    while (slots[s].entry != kEmpty) s = (s + 1) & mask;
    slots[s] = Slot{static_cast<uint32_t>(index),
                    static_cast<uint32_t>(voxel_hash(entry(index).key) >> 32)};
  }
  slots_ = std::move(slots);
}

VoxelAccumulator::Entry& VoxelAccumulator::find_or_insert(const VoxelKey& key) {
  if (2 * (size_ + 1) > slots_.size()) grow();
  const uint64_t hash = voxel_hash(key);
  const uint32_t fingerprint = static_cast<uint32_t>(hash >> 32);
  const size_t mask = slots_.size() - 1;
  for (size_t s = hash & mask;; s = (s + 1) & mask) {
    Slot& slot = slots_[s];
    if (slot.entry == kEmpty) {
      if (size_ >= kEmpty) throw std::length_error("voxel grid: more than 2^32 - 1 voxels");
      if ((size_ >> kChunkBits) == chunks_.size()) {
        chunks_.push_back(std::make_unique<Entry[]>(size_t{1} << kChunkBits));
      }
      slot = Slot{static_cast<uint32_t>(size_), fingerprint};
      Entry& created = entry(size_++);
      created.key = key;
      return created;
    }
    if (slot.fingerprint == fingerprint && entry(slot.entry).key == key) return entry(slot.entry);
  }
}

void VoxelAccumulator::add(const PointCloud& cloud) {
  if (cloud.empty()) return;
  const bool with_intensity = cloud.intensity.size() == cloud.xyz.size();
  intensity_everywhere_ = intensity_everywhere_ && with_intensity;
  for (size_t n = 0; n < cloud.xyz.size(); ++n) {
    const Eigen::Vector3f& p = cloud.xyz[n];
    if (!p.allFinite()) {
      throw std::invalid_argument("voxel grid: point " + std::to_string(n) + " is not finite");
    }
    Entry& sum = find_or_insert(voxel_of(p, inverse_leaf_));
    sum.x += p.x();
    sum.y += p.y();
    sum.z += p.z();
    if (with_intensity) sum.intensity += cloud.intensity[n];
    ++sum.count;
  }
  points_added_ += cloud.size();
}

PointCloud VoxelAccumulator::centroids() const {
  PointCloud out;
  out.xyz.reserve(size_);
  const bool with_intensity = intensity_everywhere_ && points_added_ > 0;
  if (with_intensity) out.intensity.reserve(size_);
  for (size_t index = 0; index < size_; ++index) {
    const Entry& sum = entry(index);
    const double inverse_count = 1.0 / static_cast<double>(sum.count);
    out.xyz.emplace_back(static_cast<float>(sum.x * inverse_count),
                         static_cast<float>(sum.y * inverse_count),
                         static_cast<float>(sum.z * inverse_count));
    if (with_intensity) out.intensity.push_back(static_cast<float>(sum.intensity * inverse_count));
  }
  return out;
}

void VoxelAccumulator::clear() {
  slots_ = std::vector<Slot>();
  chunks_.clear();
  size_ = 0;
  intensity_everywhere_ = true;
  points_added_ = 0;
}

}  // namespace keel::mapping
