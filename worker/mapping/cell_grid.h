// Points bucketed into cubic cells of side `cell_m`, stored cell after cell (cells in Morton
// order) as separate x, y, z float arrays. With cell_m >= r, the points within r of any point
// of cell c lie in the 3 x 3 x 3 block of cells around c: a block gathered once serves every
// query of c (the map metrics' neighbour reuse), and its contiguous columns vectorize.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace keel::mapping {

class CellGrid {
 public:
  // Throws std::invalid_argument for a non-positive or non-finite cell size or a point whose
  // cell index does not fit (see voxel_of).
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
  // Occupied cells of the 3 x 3 x 3 block centred on cell c (c included), in Morton order.
  void block_around(size_t c, std::vector<uint32_t>* cells) const;

 private:
  uint32_t find(int64_t i, int64_t j, int64_t k) const;  // kNone when unoccupied

  static constexpr uint32_t kNone = 0xffffffffu;
  std::vector<int64_t> cell_ijk_;     // 3 per cell
  std::vector<uint32_t> cell_begin_;  // cell_count + 1 offsets into the stored arrays
  std::vector<uint32_t> table_;       // open addressing: cell id or kNone
  std::vector<float> x_, y_, z_;
  std::vector<uint32_t> input_index_;
};

}  // namespace keel::mapping
