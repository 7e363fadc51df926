#include "worker/mapping/voxel_accumulator.h"

#include <algorithm>
#include <climits>
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

// The accumulator stores 32-bit indices per axis.
int32_t axis_index_32(int64_t index, float coordinate) {
  if (index < INT32_MIN || index > INT32_MAX) {
    throw std::invalid_argument("voxel grid: coordinate " + std::to_string(coordinate) +
                                " / leaf does not fit a 32-bit voxel index (leaf too small "
                                "for the extent)");
  }
  return static_cast<int32_t>(index);
}

}  // namespace

VoxelKey voxel_of(const Eigen::Vector3f& p, double inverse_leaf) {
  return VoxelKey{axis_index(p.x(), inverse_leaf), axis_index(p.y(), inverse_leaf),
                  axis_index(p.z(), inverse_leaf)};
}

VoxelAccumulator::VoxelAccumulator(double leaf_m, double merge_radius_m)
    : leaf_m_(leaf_m), inverse_leaf_(1.0 / leaf_m), merge_radius_m_(merge_radius_m) {
  if (!std::isfinite(leaf_m) || leaf_m <= 0.0) {
    throw std::invalid_argument("voxel grid: leaf must be a positive number of metres, got " +
                                std::to_string(leaf_m));
  }
  if (!(merge_radius_m >= 0.0 && merge_radius_m <= kMaxMergeLeaves * leaf_m)) {
    throw std::invalid_argument("voxel grid: merge radius must lie in [0, " +
                                std::to_string(kMaxMergeLeaves) + " leaves] = [0, " +
                                std::to_string(kMaxMergeLeaves * leaf_m) + "] m, got " +
                                std::to_string(merge_radius_m));
  }
  // A centroid within r of p lies within ceil(r / leaf) voxels of p's voxel along each axis
  // (centroids stay inside their voxel up to the small drift merged points cause).
  merge_reach_ = static_cast<int>(std::ceil(merge_radius_m * inverse_leaf_ - 1e-9));
}

VoxelAccumulator::~VoxelAccumulator() = default;
VoxelAccumulator::VoxelAccumulator(VoxelAccumulator&&) noexcept = default;
VoxelAccumulator& VoxelAccumulator::operator=(VoxelAccumulator&&) noexcept = default;

void VoxelAccumulator::grow() {
  const size_t capacity = std::max<size_t>(1024, slots_.size() * 2);
  slots_ = std::vector<uint32_t>();  // released first: the entries hold everything to rebuild
  slots_.assign(capacity, kEmpty);
  const size_t mask = capacity - 1;
  for (size_t index = 0; index < size_; ++index) {
    const Entry& e = entry(index);
    size_t s = voxel_hash(VoxelKey{e.i, e.j, e.k}) & mask;
    while (slots_[s] != kEmpty) s = (s + 1) & mask;
    slots_[s] = static_cast<uint32_t>(index);
  }
}

size_t VoxelAccumulator::probe(int32_t i, int32_t j, int32_t k, uint64_t hash) const {
  const size_t mask = slots_.size() - 1;
  for (size_t s = hash & mask;; s = (s + 1) & mask) {  // at most half full: ends
    const uint32_t slot = slots_[s];
    if (slot == kEmpty) return s;
    const Entry& e = entry(slot);
    if (e.i == i && e.j == j && e.k == k) return s;
  }
}

uint32_t VoxelAccumulator::insert_at(size_t slot, int32_t i, int32_t j, int32_t k) {
  if (size_ >= kEmpty) throw std::length_error("voxel grid: more than 2^32 - 1 voxels");
  if ((size_ >> kChunkBits) == chunks_.size()) {
    chunks_.push_back(std::make_unique<Entry[]>(size_t{1} << kChunkBits));
  }
  const uint32_t index = static_cast<uint32_t>(size_++);
  slots_[slot] = index;
  Entry& created = entry(index);
  created.i = i;
  created.j = j;
  created.k = k;
  return index;
}

uint32_t VoxelAccumulator::merge_target(const Eigen::Vector3f& p, int32_t i, int32_t j,
                                        int32_t k) const {
  uint32_t best = kEmpty;
  double best_d2 = merge_radius_m_ * merge_radius_m_;
  const int r = merge_reach_;
  for (int di = -r; di <= r; ++di) {
    for (int dj = -r; dj <= r; ++dj) {
      for (int dk = -r; dk <= r; ++dk) {
        const int64_t ni = int64_t{i} + di, nj = int64_t{j} + dj, nk = int64_t{k} + dk;
        if (ni < INT32_MIN || ni > INT32_MAX || nj < INT32_MIN || nj > INT32_MAX ||
            nk < INT32_MIN || nk > INT32_MAX) {
          continue;  // no voxel can be stored there
        }
        const uint32_t index =
            slots_[probe(static_cast<int32_t>(ni), static_cast<int32_t>(nj),
                         static_cast<int32_t>(nk), voxel_hash(VoxelKey{ni, nj, nk}))];
        if (index == kEmpty) continue;  // also the point's own voxel, empty by assumption
        const Entry& e = entry(index);
        const double inverse_count = 1.0 / static_cast<double>(e.count);
        const double ex = e.i * leaf_m_ + e.dx * inverse_count - p.x();
        const double ey = e.j * leaf_m_ + e.dy * inverse_count - p.y();
        const double ez = e.k * leaf_m_ + e.dz * inverse_count - p.z();
        const double d2 = ex * ex + ey * ey + ez * ez;
        if (d2 <= best_d2) {  // ties: the last visited in (di, dj, dk) order
          best_d2 = d2;
          best = index;
        }
      }
    }
  }
  return best;
}

void VoxelAccumulator::reserve_for(size_t more_voxels) {
  while (2 * (size_ + more_voxels) > slots_.size()) grow();
}

void VoxelAccumulator::add(const PointCloud& cloud) {
  if (cloud.empty()) return;
  for (size_t n = 0; n < cloud.xyz.size(); ++n) {
    if (!cloud.xyz[n].allFinite()) {
      throw std::invalid_argument("voxel grid: point " + std::to_string(n) + " is not finite");
    }
  }
  const bool with_intensity = cloud.intensity.size() == cloud.xyz.size();
  intensity_everywhere_ = intensity_everywhere_ && with_intensity;
  // The table is far larger than the caches on a real map, so each lookup is two cache misses
  // (slot, entry). Points go in blocks: hash the block and prefetch its slots, then prefetch
  // the entries those slots name, then accumulate, so the misses of a block overlap.
  constexpr size_t kBlock = 32;
  VoxelKey keys[kBlock];
  uint64_t hashes[kBlock];
  for (size_t begin = 0; begin < cloud.xyz.size(); begin += kBlock) {
    const size_t count = std::min(kBlock, cloud.xyz.size() - begin);
    reserve_for(count);
    const size_t mask = slots_.size() - 1;
    for (size_t b = 0; b < count; ++b) {
      keys[b] = voxel_of(cloud.xyz[begin + b], inverse_leaf_);
      hashes[b] = voxel_hash(keys[b]);
      __builtin_prefetch(&slots_[hashes[b] & mask]);
    }
    for (size_t b = 0; b < count; ++b) {
      const uint32_t slot = slots_[hashes[b] & mask];
      if (slot != kEmpty) __builtin_prefetch(&entry(slot));
    }
    for (size_t b = 0; b < count; ++b) {
      const Eigen::Vector3f& p = cloud.xyz[begin + b];
      const VoxelKey& key = keys[b];
      const int32_t i = axis_index_32(key.i, p.x()), j = axis_index_32(key.j, p.y()),
                    k = axis_index_32(key.k, p.z());
      const size_t slot = probe(i, j, k, hashes[b]);
      uint32_t index = slots_[slot];
      if (index == kEmpty && merge_reach_ > 0) {
        index = merge_target(p, i, j, k);  // inserts nothing: `slot` stays valid
        if (index != kEmpty) ++points_merged_;
      }
      if (index == kEmpty) index = insert_at(slot, i, j, k);
      // Offsets from the corner of the voxel the point joins: in [0, leaf) for its own voxel,
      // within (1 + kMaxMergeLeaves) leaves of it for a merged point; float keeps either.
      Entry& sum = entry(index);
      sum.dx += static_cast<float>(p.x() - sum.i * leaf_m_);
      sum.dy += static_cast<float>(p.y() - sum.j * leaf_m_);
      sum.dz += static_cast<float>(p.z() - sum.k * leaf_m_);
      if (with_intensity) sum.intensity += cloud.intensity[begin + b];
      ++sum.count;
    }
  }
  points_added_ += cloud.size();
}

PointCloud VoxelAccumulator::centroids(uint32_t min_hits) const {
  PointCloud out;
  const size_t kept = voxel_count(min_hits);
  out.xyz.reserve(kept);
  const bool with_intensity = intensity_everywhere_ && points_added_ > 0;
  if (with_intensity) out.intensity.reserve(kept);
  for (size_t index = 0; index < size_; ++index) {
    const Entry& sum = entry(index);
    if (sum.count < min_hits) continue;
    const double inverse_count = 1.0 / static_cast<double>(sum.count);
    out.xyz.emplace_back(static_cast<float>(sum.i * leaf_m_ + sum.dx * inverse_count),
                         static_cast<float>(sum.j * leaf_m_ + sum.dy * inverse_count),
                         static_cast<float>(sum.k * leaf_m_ + sum.dz * inverse_count));
    if (with_intensity) out.intensity.push_back(static_cast<float>(sum.intensity * inverse_count));
  }
  return out;
}

std::vector<VoxelKey> VoxelAccumulator::voxels() const {
  std::vector<VoxelKey> keys;
  keys.reserve(size_);
  for (size_t index = 0; index < size_; ++index) {
    const Entry& e = entry(index);
    keys.push_back(VoxelKey{e.i, e.j, e.k});
  }
  return keys;
}

size_t VoxelAccumulator::voxel_count(uint32_t min_hits) const {
  if (min_hits <= 1) return size_;
  size_t kept = 0;
  for (size_t index = 0; index < size_; ++index) kept += entry(index).count >= min_hits;
  return kept;
}

void VoxelAccumulator::clear() {
  slots_ = std::vector<uint32_t>();
  chunks_.clear();
  chunks_.shrink_to_fit();
  size_ = 0;
  intensity_everywhere_ = true;
  points_added_ = 0;
  points_merged_ = 0;
}

}  // namespace keel::mapping
