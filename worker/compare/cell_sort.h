// Points sorted by the cubic cell they fall in: the first step of voxelize() and of PointGrid.
// A cell's key packs its (x, y, z) indices from the cloud's lowest corner, x most significant,
// with only as many bits per axis as the cloud spans (about 28 for a 170 m bridge map in 10 cm
// cells), so a stable radix sort of 11-bit digits orders ten million points in three passes,
// where std::sort of (key, index) pairs compared 64-bit keys ~23 times a point. Stable from
// index order, it gives that sort's exact order: keys ascending, each cell's points by index.
#pragma once

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace keel::compare {

// Cells are indexed up to 2^21 along each axis (at 1 cm that is 20 km).
inline constexpr int kCellAxisBits = 21;

// (key, point index) entries, sorted by key keeping the order of equal keys (stable LSD radix
// sort, 11 bits a pass). Keys of up to 32 bits (a map of a few hundred metres in 10 cm cells)
// share one 64-bit word with the index: half the memory of a pair, and half the bytes each
// pass moves and each fresh page the kernel clears.
class KeyedIndices {
 public:
  KeyedIndices() = default;
  KeyedIndices(size_t n, int key_bits);
  void set(size_t k, uint64_t key, uint32_t index) {
    if (packed()) {
      words_[k] = key << 32 | index;
    } else {
      pairs_[k] = {key, index};
    }
  }
  uint64_t key(size_t k) const { return packed() ? words_[k] >> 32 : pairs_[k].first; }
  uint32_t index(size_t k) const { return packed() ? uint32_t(words_[k]) : pairs_[k].second; }
  size_t size() const { return packed() ? words_.size() : pairs_.size(); }
  void sort();

 private:
  bool packed() const { return key_bits_ <= 32; }
  int key_bits_ = 0;
  std::vector<uint64_t> words_;
  std::vector<std::pair<uint64_t, uint32_t>> pairs_;
};

struct CellSort {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // the points' minimum: cell (0, 0, 0)'s corner
  double cell_m = 0.0;
  std::array<int, 3> bits = {0, 0, 0};       // key bits of x, y, z
  std::array<int64_t, 3> cells = {0, 0, 0};  // the cells' indices lie in [0, cells) per axis
  // (cell key, point index), keys ascending, each cell's points in increasing index order.
  KeyedIndices keyed;

  // The cell's (x, y, z) indices.
  std::array<int64_t, 3> cell_of_key(uint64_t key) const;
};

// `what` prefixes the messages: throws std::invalid_argument for a non-positive cell size, a
// non-finite point, or a cloud spanning more than 2^21 cells along an axis. Keys are computed
// on `threads` threads.
CellSort sort_into_cells(const std::vector<Eigen::Vector3f>& points, double cell_m,
                         const std::string& what, int threads = 1);

}  // namespace keel::compare
