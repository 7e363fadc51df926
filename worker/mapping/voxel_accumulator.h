// Running voxel centroids: points are added in any number of batches and the result equals one
// VoxelGrid pass over their union (sums, not centroids of centroids, are kept). Memory grows
// with the number of occupied voxels, not with the points added, which is what lets
// MapBuilder stream a long mission into a voxelized map at constant memory per structure.
//
// Optional merge rule (merge_radius_m > 0): a point whose voxel is still empty joins the
// occupied voxel, among those within ceil(merge_radius / leaf) indices per axis, whose current
// centroid is nearest to it, if that centroid lies within the merge radius; only otherwise does
// it open its voxel. Why: a plain voxel grid bounds the map by the surfaces' area only once
// every voxel of the range-noise shell around them is occupied, and a shell several voxels
// thick (lidar range noise sigma = 1 cm against a 2 cm leaf) keeps opening voxels as a survey
// samples it more densely, so a slower survey of the same structure gives a larger map. With
// the rule a voxel opens only for a point farther than the merge radius from every nearby
// centroid, so occupied voxels are seeded at least ~one merge radius apart: the map saturates
// at about one point per merge-radius ball of the sampled shell, whatever the sampling density.
// The price: the result depends on the order of the points (MapBuilder commits scans in feed
// order, so its maps stay deterministic), and it is no longer exactly pcl::VoxelGrid.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <memory>
#include <vector>

#include "core/point_cloud.h"

namespace keel::mapping {

struct VoxelKey {
  int64_t i = 0, j = 0, k = 0;
  bool operator==(const VoxelKey& other) const {
    return i == other.i && j == other.j && k == other.k;
  }
};

// 64-bit mix of the three indices (multiply-xorshift; full avalanche so linear probing does
// not cluster on the regular structure of voxel indices).
inline uint64_t voxel_hash(const VoxelKey& key) {
  uint64_t h = static_cast<uint64_t>(key.i) * 0x9e3779b97f4a7c15ULL;
  h ^= static_cast<uint64_t>(key.j) * 0xc2b2ae3d27d4eb4fULL;
  h ^= static_cast<uint64_t>(key.k) * 0x165667b19e3779f9ULL;
  h ^= h >> 32;
  h *= 0xd6e8feb86659fd93ULL;
  h ^= h >> 32;
  return h;
}

// The voxel of a point: floor(p / leaf) per axis, anchored at the origin like pcl::VoxelGrid.
// Throws std::invalid_argument when p / leaf does not fit a 62-bit index (absurd leaf sizes).
VoxelKey voxel_of(const Eigen::Vector3f& p, double inverse_leaf);

class VoxelAccumulator {
 public:
  // Throws std::invalid_argument unless leaf_m is finite and positive and merge_radius_m is
  // in [0, kMaxMergeLeaves * leaf_m] (0: a plain voxel grid; see the merge rule above).
  explicit VoxelAccumulator(double leaf_m, double merge_radius_m = 0.0);
  // The search visits (2 ceil(r / leaf) + 1)^3 - 1 voxels per point landing in an empty one.
  static constexpr double kMaxMergeLeaves = 2.0;
  ~VoxelAccumulator();
  VoxelAccumulator(VoxelAccumulator&&) noexcept;
  VoxelAccumulator& operator=(VoxelAccumulator&&) noexcept;

  // Adds every point (non-finite ones throw, as do points whose voxel index along an axis
  // does not fit 32 bits: beyond +-21,000 km at a 1 cm leaf). Intensity is averaged when every
  // cloud added carries it.
  void add(const PointCloud& cloud);
  // One point per voxel holding at least `min_hits` points, the centroid, in the order the
  // voxels were first occupied (so one pass over a cloud and any split of it into consecutive
  // batches give the same output; with merging, as long as the point order is kept).
  PointCloud centroids(uint32_t min_hits = 1) const;
  // The index of each occupied voxel, in the order of centroids() (min_hits 1).
  std::vector<VoxelKey> voxels() const;
  // Voxels holding at least `min_hits` points.
  size_t voxel_count(uint32_t min_hits) const;

  size_t voxel_count() const { return size_; }
  uint64_t points_added() const { return points_added_; }
  double leaf_m() const { return leaf_m_; }
  double merge_radius_m() const { return merge_radius_m_; }
  // Points added to an empty voxel's occupied neighbour by the merge rule.
  uint64_t points_merged() const { return points_merged_; }
  void clear();

 private:
  // 32 bytes per voxel: the index (32 bits per axis), the hit count, and float sums of the
  // points' offsets from the voxel's corner (offsets lie in [0, leaf), so float sums keep
  // ~1e-7 relative precision of the leaf, unlike float sums of world coordinates). Entries
  // live in fixed-size chunks so growth never copies them; the open-addressing index holds
  // 4-byte entry numbers (linear probing, at most half full): ~40-48 bytes per voxel in all,
  // against ~110 for std::unordered_map with double sums.
  struct Entry {
    int32_t i = 0, j = 0, k = 0;
    uint32_t count = 0;
    float dx = 0.f, dy = 0.f, dz = 0.f;
    float intensity = 0.f;
  };
  static constexpr uint32_t kEmpty = 0xffffffffu;
  static constexpr size_t kChunkBits = 16;

  Entry& entry(size_t index) {
    return chunks_[index >> kChunkBits][index & ((size_t{1} << kChunkBits) - 1)];
  }
  const Entry& entry(size_t index) const {
    return chunks_[index >> kChunkBits][index & ((size_t{1} << kChunkBits) - 1)];
  }
  // `hash` = voxel_hash of the index. The slot holding the voxel, or the empty slot where it
  // would go.
  size_t probe(int32_t i, int32_t j, int32_t k, uint64_t hash) const;
  // Opens voxel (i, j, k) in the empty slot `slot` (from probe, no insertion since); the table
  // must have room for one more voxel. Returns its entry number.
  uint32_t insert_at(size_t slot, int32_t i, int32_t j, int32_t k);
  // The merge rule: the entry number of the occupied voxel near (i, j, k) whose centroid is
  // nearest p and within the merge radius, or kEmpty.
  uint32_t merge_target(const Eigen::Vector3f& p, int32_t i, int32_t j, int32_t k) const;
  void reserve_for(size_t more_voxels);  // grows until size + more fits at half load
  void grow();

  double leaf_m_;
  double inverse_leaf_;
  double merge_radius_m_ = 0.0;
  int merge_reach_ = 0;  // ceil(merge radius / leaf): voxels searched per axis and side
  uint64_t points_merged_ = 0;
  bool intensity_everywhere_ = true;
  uint64_t points_added_ = 0;
  size_t size_ = 0;
  std::vector<uint32_t> slots_;  // entry numbers; power-of-two size, at most half full
  std::vector<std::unique_ptr<Entry[]>> chunks_;
};

}  // namespace keel::mapping
