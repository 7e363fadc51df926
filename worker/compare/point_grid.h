// A dense cloud's points bucketed into cubic cells found through a hash table, for the queries
// the compare stage makes around every point of a map: C2C's nearest point and M3C2's
// cylinders. On a map voxel-filtered at ~2 cm a 10 cm cell holds ~25 points of surface, so a
// nearest-point query reads its own cell and the few neighbours its distance reaches, and a
// cylinder reads only the cells along its axis, where a kd-tree's radius search gathers the
// whole sphere around it (~7 times the points at M3C2's short depth, ~50 at its full depth).
// Queries are const and may run concurrently.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

#include "worker/compare/cell_sort.h"
#include "worker/compare/nearest_index.h"

namespace keel::compare {

class PointGrid {
 public:
  // Copies the points, cell after cell. Throws std::invalid_argument for an empty set, a
  // non-finite point, a non-positive cell size or a cloud wider than 2^21 cells.
  PointGrid(const std::vector<Eigen::Vector3f>& points, double cell_m, int threads = 1);
  ~PointGrid();
  PointGrid(const PointGrid&) = delete;
  PointGrid& operator=(const PointGrid&) = delete;

  // The point closest to `query`, exactly (index into the constructor's points; the lowest
  // among exact ties is not promised), its distance computed in double as NearestIndex does.
  Neighbour nearest(const Eigen::Vector3f& query) const;

  // A run of stored points: points()[begin, end).
  struct Run {
    uint32_t begin = 0, end = 0;
  };
  // The runs of every cell that may hold a point within radius_m of the segment [from, to]:
  // every such point is in them (with others near it).
  void near_segment(const Eigen::Vector3d& from, const Eigen::Vector3d& to, double radius_m,
                    std::vector<Run>* runs) const;

  // The points in cell order, and each one's index in the constructor's points.
  const std::vector<Eigen::Vector3f>& points() const { return points_; }
  const std::vector<uint32_t>& input_index() const { return input_index_; }
  size_t size() const { return points_.size(); }
  double cell_m() const { return cell_m_; }

 private:
  void index_box(const std::vector<uint64_t>& cell_key, const CellSort& sorted);
  void index_hash(const std::vector<uint64_t>& cell_key);
  // The cell's number, or -1 when no point lies in it.
  int64_t find(int64_t x, int64_t y, int64_t z) const;
  // Cell indices of a position (floored, possibly outside the occupied range).
  Eigen::Array<int64_t, 3, 1> cell_of(const Eigen::Vector3d& p) const;
  // nearest() beyond the rings of cells around the query: through a kd-tree over the cells'
  // centres, built on first use.
  void nearest_far(const Eigen::Vector3d& q, double* best, uint32_t* best_entry) const;
  void scan(uint32_t cell, const Eigen::Vector3d& q, double* best_squared,
            uint32_t* best_entry) const;

  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
  double cell_m_ = 0.0, inverse_cell_ = 0.0;
  int64_t extent_[3] = {0, 0, 0};     // occupied cells lie in [0, extent) along each axis
  int shift_x_ = 0, shift_y_ = 0;     // a cell's key: x << shift_x_ | y << shift_y_ | z
  std::vector<uint32_t> cell_begin_;  // per cell its first point, then size()
  // A cell's number, found one of two ways. Over a compact box (at most 64 cells per point, as
  // a surface map's): one bit per cell of the box, x major like the cells' order, so a cell's
  // number is the count of bits set before its own (per 64-bit word, then a popcount), and
  // neighbouring cells share cache lines. Otherwise an open-addressing hash table of keys.
  std::vector<uint64_t> occupied_;
  std::vector<uint32_t> occupied_before_;  // per word of occupied_, the bits set before it
  struct Slot {
    uint64_t key;
    uint32_t cell;
  };
  std::vector<Slot> slots_;
  uint64_t slot_mask_ = 0;
  std::vector<Eigen::Vector3f> points_;
  std::vector<uint32_t> input_index_;
  mutable std::once_flag far_once_;
  mutable std::unique_ptr<NearestIndex> far_;  // cell centres, cell order
};

}  // namespace keel::compare
