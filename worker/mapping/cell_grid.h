// Points bucketed into cubic cells of side `cell_m`, stored cell after cell as separate x, y, z
// float arrays, cells in lexicographic (i, j, k) order. With cell_m >= r, the points within r
// of any point of cell c lie in the 3 x 3 x 3 block of cells around c: a block gathered once
// serves every query of c (the map metrics' neighbour reuse), and its contiguous columns
// vectorize. In (i, j, k) order a block is nine runs of consecutive cells (one per column
// (i + di, j + dj)), and a sweep over cells in increasing order finds each run by advancing one
// pointer per column: no hashing, no random access.
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace keel::mapping {

class CellGrid {
 public:
  // Throws std::invalid_argument for a non-positive or non-finite cell size, a non-finite
  // point, or a cell index beyond 2^62 (coordinate / cell_m).
  CellGrid(const std::vector<Eigen::Vector3f>& points, double cell_m);

  size_t cell_count() const { return cell_begin_.size() - 1; }
  // Stored points of cell c: [begin(c), end(c)).
  uint32_t begin(size_t c) const { return cell_begin_[c]; }
  uint32_t end(size_t c) const { return cell_begin_[c + 1]; }
  const std::vector<float>& x() const { return x_; }
  const std::vector<float>& y() const { return y_; }
  const std::vector<float>& z() const { return z_; }
  // input_index()[i]: the index in the constructor's input of stored point i.
  const std::vector<uint32_t>& input_index() const { return input_index_; }
  // Occupied cells of the 3 x 3 x 3 block centred on cell c (c included), increasing. One
  // binary search per column; BlockFinder is faster for a sweep.
  void block_around(size_t c, std::vector<uint32_t>* cells) const;

  // Blocks of cells visited in increasing order cost a few comparisons each (a visit to an
  // earlier cell restarts with binary searches). One per thread.
  class BlockFinder {
   public:
    explicit BlockFinder(const CellGrid& grid) : grid_(&grid) {}
    void block_around(size_t c, std::vector<uint32_t>* cells);

   private:
    const CellGrid* grid_;
    size_t last_ = 0;
    bool started_ = false;
    size_t column_[9] = {};  // first cell not below the column's run, per (di, dj)
  };

 private:
  // Cell (i, j, k) packed as i << shift_i_ | j << shift_j_ | k over the occupied index ranges
  // (gap-compressed when wide), with one free index on either side so that a neighbour's key
  // is the cell's key plus a constant.
  std::vector<uint64_t> cell_key_;
  uint64_t shift_i_ = 0, shift_j_ = 0;
  std::vector<uint32_t> cell_begin_;  // cell_count + 1 offsets into the stored arrays
  std::vector<float> x_, y_, z_;
  std::vector<uint32_t> input_index_;
};

}  // namespace keel::mapping
