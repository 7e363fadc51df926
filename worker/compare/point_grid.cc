#include "worker/compare/point_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "worker/compare/cell_sort.h"

namespace keel::compare {
namespace {

constexpr uint64_t kEmpty = ~uint64_t(0);
// Rings of cells searched around a nearest-point query before the kd-tree over cell centres
// takes over: two rings certify any distance up to two cells, which covers nearly every point
// of a survey against the one before it (C2C above 20 cm: ~0.1 % of the bridge's points).
constexpr int kRings = 2;
// Allowance for rounding where a cell's box or centre bounds a point's distance: far above
// double rounding of coordinates of a few km, far below any distance of interest.
constexpr double kSlack = 1e-9;

uint64_t slot_of(uint64_t key, uint64_t mask) {
  key ^= key >> 31;  // neighbouring cells' keys differ in a few low bits of each axis: mix them
  key *= 0xbf58476d1ce4e5b9ULL;
  key ^= key >> 29;
  return key & mask;
}

}  // namespace

PointGrid::PointGrid(const std::vector<Eigen::Vector3f>& points, double cell_m, int threads) {
  if (points.empty()) throw std::invalid_argument("point grid: no points");
  if (points.size() >= 0xffffffffu) throw std::invalid_argument("point grid: over 2^32 points");
  const CellSort sorted = sort_into_cells(points, cell_m, "point grid", threads);
  origin_ = sorted.origin;
  cell_m_ = cell_m;
  inverse_cell_ = 1.0 / cell_m;
  shift_x_ = sorted.bits[1] + sorted.bits[2];
  shift_y_ = sorted.bits[2];
  for (int axis = 0; axis < 3; ++axis) extent_[axis] = sorted.cells[axis];

  points_.resize(points.size());
  input_index_.resize(points.size());
  std::vector<uint64_t> cell_key;
  for (size_t k = 0; k < sorted.keyed.size(); ++k) {
    const uint64_t key = sorted.keyed.key(k);
    const uint32_t index = sorted.keyed.index(k);
    if (k == 0 || key != sorted.keyed.key(k - 1)) {
      cell_key.push_back(key);
      cell_begin_.push_back(uint32_t(k));
    }
    points_[k] = points[index];
    input_index_[k] = index;
  }
  cell_begin_.push_back(uint32_t(points.size()));

  const double box_cells = double(extent_[0]) * double(extent_[1]) * double(extent_[2]);
  if (box_cells <= 64.0 * double(points.size()))
    index_box(cell_key, sorted);
  else
    index_hash(cell_key);
}

void PointGrid::index_box(const std::vector<uint64_t>& cell_key, const CellSort& sorted) {
  occupied_.assign(size_t((extent_[0] * extent_[1] * extent_[2] + 63) / 64), 0);
  for (const uint64_t key : cell_key) {
    const auto [x, y, z] = sorted.cell_of_key(key);
    const uint64_t bit = uint64_t((x * extent_[1] + y) * extent_[2] + z);
    occupied_[bit >> 6] |= uint64_t(1) << (bit & 63);
  }
  occupied_before_.resize(occupied_.size());
  uint32_t count = 0;
  for (size_t w = 0; w < occupied_.size(); ++w) {
    occupied_before_[w] = count;
    count += uint32_t(__builtin_popcountll(occupied_[w]));
  }
}

void PointGrid::index_hash(const std::vector<uint64_t>& cell_key) {
  size_t slots = 1;
  while (slots < 2 * cell_key.size()) slots *= 2;
  slot_mask_ = slots - 1;
  slots_.assign(slots, {kEmpty, 0});
  for (size_t c = 0; c < cell_key.size(); ++c) {
    uint64_t slot = slot_of(cell_key[c], slot_mask_);
    while (slots_[slot].key != kEmpty) slot = (slot + 1) & slot_mask_;
    slots_[slot] = {cell_key[c], uint32_t(c)};
  }
}

PointGrid::~PointGrid() = default;

int64_t PointGrid::find(int64_t x, int64_t y, int64_t z) const {
  if (x < 0 || y < 0 || z < 0 || x >= extent_[0] || y >= extent_[1] || z >= extent_[2]) return -1;
  if (!occupied_.empty()) {
    const uint64_t bit = uint64_t((x * extent_[1] + y) * extent_[2] + z);
    const uint64_t word = occupied_[bit >> 6], mask = uint64_t(1) << (bit & 63);
    if (!(word & mask)) return -1;
    return occupied_before_[bit >> 6] + __builtin_popcountll(word & (mask - 1));
  }
  const uint64_t key = uint64_t(x) << shift_x_ | uint64_t(y) << shift_y_ | uint64_t(z);
  for (uint64_t slot = slot_of(key, slot_mask_);; slot = (slot + 1) & slot_mask_) {
    if (slots_[slot].key == key) return slots_[slot].cell;
    if (slots_[slot].key == kEmpty) return -1;
  }
}

Eigen::Array<int64_t, 3, 1> PointGrid::cell_of(const Eigen::Vector3d& p) const {
  // Clamped far outside the occupied range, so that neighbours' indices cannot overflow.
  const Eigen::Array3d c = ((p - origin_) * inverse_cell_).array().floor().max(-1e15).min(1e15);
  return c.cast<int64_t>();
}

void PointGrid::scan(uint32_t cell, const Eigen::Vector3d& q, double* best_squared,
                     uint32_t* best_entry) const {
  for (uint32_t e = cell_begin_[cell]; e < cell_begin_[cell + 1]; ++e) {
    const double d2 = (points_[e].cast<double>() - q).squaredNorm();
    if (d2 < *best_squared) *best_squared = d2, *best_entry = e;
  }
}

Neighbour PointGrid::nearest(const Eigen::Vector3f& query) const {
  const Eigen::Vector3d q = query.cast<double>();
  const Eigen::Array<int64_t, 3, 1> k0 = cell_of(q);
  // gap[axis][kRings + d]: the distance along the axis from q to the cells d steps away.
  double gap[3][2 * kRings + 1];
  double inside = std::numeric_limits<double>::infinity();  // q to its own cell's nearest face
  for (int axis = 0; axis < 3; ++axis) {
    const double below = q[axis] - (origin_[axis] + double(k0[axis]) * cell_m_);
    const double above = cell_m_ - below;
    inside = std::min({inside, below, above});
    gap[axis][kRings] = 0.0;
    for (int d = 1; d <= kRings; ++d) {
      gap[axis][kRings - d] = std::max(0.0, below + (d - 1) * cell_m_ - kSlack);
      gap[axis][kRings + d] = std::max(0.0, above + (d - 1) * cell_m_ - kSlack);
    }
  }
  double best_squared = std::numeric_limits<double>::infinity();
  uint32_t best_entry = 0;
  for (int ring = 0; ring <= kRings; ++ring) {
    for (int dx = -ring; dx <= ring; ++dx) {
      const double gx = gap[0][kRings + dx] * gap[0][kRings + dx];
      if (gx > best_squared) continue;
      for (int dy = -ring; dy <= ring; ++dy) {
        const double gxy = gx + gap[1][kRings + dy] * gap[1][kRings + dy];
        if (gxy > best_squared) continue;
        const bool shell = std::abs(dx) == ring || std::abs(dy) == ring;
        // Within the ring's shell every dz; otherwise only its two faces.
        for (int dz = -ring; dz <= ring; dz += shell || ring == 0 ? 1 : 2 * ring) {
          // A cell whose box lies farther than the best so far cannot hold a nearer point.
          if (gxy + gap[2][kRings + dz] * gap[2][kRings + dz] > best_squared) continue;
          const int64_t cell = find(k0.x() + dx, k0.y() + dy, k0.z() + dz);
          if (cell >= 0) scan(uint32_t(cell), q, &best_squared, &best_entry);
        }
      }
    }
    // Every cell not visited lies beyond the block of rings searched.
    const double bound = ring * cell_m_ + inside - kSlack;
    if (bound > 0.0 && best_squared <= bound * bound) break;
    if (ring == kRings) nearest_far(q, &best_squared, &best_entry);
  }
  return {input_index_[best_entry], std::sqrt(best_squared)};
}

void PointGrid::nearest_far(const Eigen::Vector3d& q, double* best_squared,
                            uint32_t* best_entry) const {
  std::call_once(far_once_, [this] {
    std::vector<Eigen::Vector3f> centres(cell_begin_.size() - 1);
    for (size_t c = 0; c + 1 < cell_begin_.size(); ++c) {
      const Eigen::Array<int64_t, 3, 1> k = cell_of(points_[cell_begin_[c]].cast<double>());
      centres[c] = (origin_.array() + (k.cast<double>() + 0.5) * cell_m_).matrix().cast<float>();
    }
    far_ = std::make_unique<NearestIndex>(centres);
  });
  // Each point lies within `half` of its cell's centre: the nearest centre bounds the nearest
  // point's distance, and the nearest point's cell has its centre within that bound + half.
  // The float centres are off by ~1e-5 m at a few hundred metres: a margin covers that.
  const double half = 0.5 * std::sqrt(3.0) * cell_m_, margin = 1e-4 + 1e-6 * q.norm();
  const Eigen::Vector3f query = q.cast<float>();
  const double upper = std::min(std::sqrt(*best_squared), far_->nearest(query).distance_m + half);
  std::vector<uint32_t> cells;
  far_->within(query, upper + half + 2.0 * margin, &cells);
  for (const uint32_t c : cells) scan(c, q, best_squared, best_entry);
}

void PointGrid::near_segment(const Eigen::Vector3d& from, const Eigen::Vector3d& to,
                             double radius_m, std::vector<Run>* runs) const {
  runs->clear();
  const Eigen::Vector3d lo = from.cwiseMin(to).array() - radius_m;
  const Eigen::Vector3d hi = from.cwiseMax(to).array() + radius_m;
  const Eigen::Array<int64_t, 3, 1> first = cell_of(lo).max(0);
  const Eigen::Array<int64_t, 3, 1> last =
      cell_of(hi).min(Eigen::Array<int64_t, 3, 1>(extent_[0], extent_[1], extent_[2]) - 1);
  if ((first > last).any()) return;
  // A point within r of the segment lies in a cell whose centre is within r + half a cell's
  // diagonal of it (distance to a segment changes no faster than the point moves).
  const double reach = radius_m + 0.5 * std::sqrt(3.0) * cell_m_ + kSlack;
  const Eigen::Vector3d axis = to - from;
  const double length_squared = axis.squaredNorm();
  auto add_if_near = [&](int64_t x, int64_t y, int64_t z, uint32_t cell) {
    const Eigen::Vector3d centre =
        origin_ +
        (Eigen::Vector3d(double(x), double(y), double(z)).array() + 0.5).matrix() * cell_m_;
    const Eigen::Vector3d v = centre - from;
    const double t =
        length_squared > 0.0 ? std::clamp(v.dot(axis) / length_squared, 0.0, 1.0) : 0.0;
    if ((v - t * axis).squaredNorm() <= reach * reach)
      runs->push_back({cell_begin_[cell], cell_begin_[cell + 1]});
  };
  for (int64_t x = first.x(); x <= last.x(); ++x)
    for (int64_t y = first.y(); y <= last.y(); ++y) {
      if (occupied_.empty()) {
        for (int64_t z = first.z(); z <= last.z(); ++z)
          if (const int64_t cell = find(x, y, z); cell >= 0) add_if_near(x, y, z, uint32_t(cell));
        continue;
      }
      // Only the occupied cells of the column: the set bits between its first and last z
      // (most cells around a cylinder are empty, the surface crossing it is thin).
      const uint64_t base = uint64_t((x * extent_[1] + y) * extent_[2]);
      const uint64_t begin = base + uint64_t(first.z()), end = base + uint64_t(last.z()) + 1;
      for (uint64_t w = begin >> 6; w <= (end - 1) >> 6; ++w) {
        uint64_t bits = occupied_[w];
        if (w == begin >> 6) bits &= ~uint64_t(0) << (begin & 63);
        if (w == (end - 1) >> 6 && (end & 63) != 0) bits &= (uint64_t(1) << (end & 63)) - 1;
        for (; bits != 0; bits &= bits - 1) {
          const uint64_t bit = (w << 6) + uint64_t(__builtin_ctzll(bits));
          const uint32_t cell =
              occupied_before_[w] +
              uint32_t(__builtin_popcountll(occupied_[w] & ((uint64_t(1) << (bit & 63)) - 1)));
          add_if_near(x, y, int64_t(bit - base), cell);
        }
      }
    }
}

}  // namespace keel::compare
