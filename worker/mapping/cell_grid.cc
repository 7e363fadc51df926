#include "worker/mapping/cell_grid.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "worker/mapping/voxel_accumulator.h"

namespace keel::mapping {
namespace {

// Spreads the low 21 bits of v so that two zero bits separate each (Morton interleaving).
uint64_t spread_bits(uint64_t v) {
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffULL;
  v = (v | v << 16) & 0x1f0000ff0000ffULL;
  v = (v | v << 8) & 0x100f00f00f00f00fULL;
  v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
  v = (v | v << 2) & 0x1249249249249249ULL;
  return v;
}

// Only orders cells (wrapping past 2^21 cells per axis costs locality, not correctness).
uint64_t morton(const int64_t* ijk) {
  return spread_bits(static_cast<uint64_t>(ijk[0])) |
         spread_bits(static_cast<uint64_t>(ijk[1])) << 1 |
         spread_bits(static_cast<uint64_t>(ijk[2])) << 2;
}

size_t table_capacity(size_t entries) {
  size_t capacity = 16;
  while (capacity < 2 * entries) capacity *= 2;
  return capacity;
}

}  // namespace

CellGrid::CellGrid(const std::vector<Eigen::Vector3f>& points, double cell_m) {
  if (!std::isfinite(cell_m) || cell_m <= 0.0) {
    throw std::invalid_argument("cell grid: cell size must be a positive number of metres, got " +
                                std::to_string(cell_m));
  }
  if (points.size() >= kNone) throw std::invalid_argument("cell grid: more than 2^32 - 1 points");
  const double inverse_cell = 1.0 / cell_m;
  // Pass 1: provisional cell ids in order of first appearance, via the open-addressing table.
  table_.assign(table_capacity(points.size()), kNone);
  std::vector<uint32_t> cell_of_point(points.size());
  std::vector<uint32_t> counts;
  size_t mask = table_.size() - 1;
  for (size_t n = 0; n < points.size(); ++n) {
    const VoxelKey key = voxel_of(points[n], inverse_cell);
    size_t s = voxel_hash(key) & mask;
    while (table_[s] != kNone) {
      const int64_t* ijk = &cell_ijk_[3 * table_[s]];
      if (ijk[0] == key.i && ijk[1] == key.j && ijk[2] == key.k) break;
      s = (s + 1) & mask;
    }
    if (table_[s] == kNone) {
      table_[s] = static_cast<uint32_t>(counts.size());
      cell_ijk_.insert(cell_ijk_.end(), {key.i, key.j, key.k});
      counts.push_back(0);
    }
    cell_of_point[n] = table_[s];
    ++counts[table_[s]];
  }
  // Cells in Morton order so that neighbouring blocks share most of their cells in cache.
  const size_t cells = counts.size();
  std::vector<std::pair<uint64_t, uint32_t>> keyed(cells);
  for (size_t c = 0; c < cells; ++c)
    keyed[c] = {morton(&cell_ijk_[3 * c]), static_cast<uint32_t>(c)};
  std::sort(keyed.begin(), keyed.end());
  std::vector<uint32_t> final_id(cells);
  std::vector<int64_t> ijk(3 * cells);
  cell_begin_.assign(cells + 1, 0);
  for (size_t c = 0; c < cells; ++c) {
    const uint32_t old = keyed[c].second;
    final_id[old] = static_cast<uint32_t>(c);
    std::copy_n(&cell_ijk_[3 * old], 3, &ijk[3 * c]);
    cell_begin_[c + 1] = cell_begin_[c] + counts[old];
  }
  cell_ijk_ = std::move(ijk);
  table_.assign(table_capacity(cells), kNone);
  mask = table_.size() - 1;
  for (size_t c = 0; c < cells; ++c) {
    const int64_t* key = &cell_ijk_[3 * c];
    size_t s = voxel_hash(VoxelKey{key[0], key[1], key[2]}) & mask;
    while (table_[s] != kNone) s = (s + 1) & mask;
    table_[s] = static_cast<uint32_t>(c);
  }
  // Pass 2: scatter the points cell by cell.
  std::vector<uint32_t> next(cell_begin_.begin(), cell_begin_.end() - 1);
  x_.resize(points.size());
  y_.resize(points.size());
  z_.resize(points.size());
  input_index_.resize(points.size());
  for (size_t n = 0; n < points.size(); ++n) {
    const uint32_t i = next[final_id[cell_of_point[n]]]++;
    x_[i] = points[n].x();
    y_[i] = points[n].y();
    z_[i] = points[n].z();
    input_index_[i] = static_cast<uint32_t>(n);
  }
}

uint32_t CellGrid::find(int64_t i, int64_t j, int64_t k) const {
  const size_t mask = table_.size() - 1;
  for (size_t s = voxel_hash(VoxelKey{i, j, k}) & mask; table_[s] != kNone; s = (s + 1) & mask) {
    const int64_t* ijk = &cell_ijk_[3 * table_[s]];
    if (ijk[0] == i && ijk[1] == j && ijk[2] == k) return table_[s];
  }
  return kNone;
}

void CellGrid::block_around(size_t c, std::vector<uint32_t>* cells) const {
  cells->clear();
  const int64_t* ijk = &cell_ijk_[3 * c];
  for (int64_t di = -1; di <= 1; ++di) {
    for (int64_t dj = -1; dj <= 1; ++dj) {
      for (int64_t dk = -1; dk <= 1; ++dk) {
        const uint32_t id = find(ijk[0] + di, ijk[1] + dj, ijk[2] + dk);
        if (id != kNone) cells->push_back(id);
      }
    }
  }
  std::sort(cells->begin(), cells->end());
}

}  // namespace keel::mapping
