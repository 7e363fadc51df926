#include "worker/mapping/cell_grid.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace keel::mapping {
namespace {

// floor(coordinate / cell) like voxel_of; |index| < 2^62 keeps index +- 1 and key differences
// free of overflow.
int64_t cell_index(float coordinate, double inverse_cell) {
  const double scaled = std::floor(static_cast<double>(coordinate) * inverse_cell);
  constexpr double kLimit = 4.611686018427388e18;
  if (!(std::abs(scaled) < kLimit)) {
    throw std::invalid_argument("cell grid: coordinate " + std::to_string(coordinate) +
                                " / cell size does not fit a 62-bit cell index");
  }
  return static_cast<int64_t>(scaled);
}

int bits_for(uint64_t largest) {
  int bits = 0;
  while (bits < 64 && (largest >> bits) != 0) ++bits;
  return bits;
}

// Cell indices along one axis to small codes that keep order and adjacency (index + 1 gets
// code + 1; a larger gap gets a code gap of 2), with codes 0 and extent - 1 left free.
class AxisCode {
 public:
  // Dense: code = index - min + 1.
  AxisCode(int64_t min, int64_t max)
      : min_(min), largest_(static_cast<uint64_t>(max) - static_cast<uint64_t>(min) + 2) {}
  // Gap-compressed over the indices present, for extents too wide to pack densely.
  explicit AxisCode(std::vector<int64_t> indices) {
    std::sort(indices.begin(), indices.end());
    indices.erase(std::unique(indices.begin(), indices.end()), indices.end());
    distinct_ = std::move(indices);
    codes_.resize(distinct_.size());
    uint64_t code = 1;
    for (size_t t = 0; t < distinct_.size(); ++t) {
      if (t > 0) code += distinct_[t] - distinct_[t - 1] == 1 ? 1 : 2;
      codes_[t] = code;
    }
    largest_ = code + 1;
  }
  uint64_t operator()(int64_t index) const {
    if (distinct_.empty()) return static_cast<uint64_t>(index) - static_cast<uint64_t>(min_) + 1;
    const auto at = std::lower_bound(distinct_.begin(), distinct_.end(), index);
    return codes_[static_cast<size_t>(at - distinct_.begin())];
  }
  int bits() const { return bits_for(largest_); }

 private:
  int64_t min_ = 0;
  uint64_t largest_ = 0;  // the free code above every index's
  std::vector<int64_t> distinct_;
  std::vector<uint64_t> codes_;
};

struct Entry {
  uint64_t key;
  uint32_t index;
};

// Stable LSD radix sort on the low `bits` bits of the keys, 11 bits a pass.
void radix_sort(std::vector<Entry>* entries, int bits) {
  constexpr int kDigit = 11;
  constexpr size_t kBuckets = size_t{1} << kDigit;
  std::vector<Entry> other(entries->size());
  std::vector<size_t> offsets(kBuckets);
  for (int shift = 0; shift < bits; shift += kDigit) {
    std::fill(offsets.begin(), offsets.end(), 0);
    for (const Entry& e : *entries) ++offsets[(e.key >> shift) & (kBuckets - 1)];
    size_t total = 0;
    for (size_t& offset : offsets) total += std::exchange(offset, total);
    for (const Entry& e : *entries) other[offsets[(e.key >> shift) & (kBuckets - 1)]++] = e;
    entries->swap(other);
  }
}

}  // namespace

CellGrid::CellGrid(const std::vector<Eigen::Vector3f>& points, double cell_m) {
  if (!std::isfinite(cell_m) || cell_m <= 0.0) {
    throw std::invalid_argument("cell grid: cell size must be a positive number of metres, got " +
                                std::to_string(cell_m));
  }
  if (points.size() >= 0xffffffffu) {
    throw std::invalid_argument("cell grid: more than 2^32 - 1 points");
  }
  const double inverse_cell = 1.0 / cell_m;
  cell_begin_.assign(1, 0);
  if (points.empty()) return;
  Eigen::Vector3f low = points.front(), high = points.front();
  for (size_t n = 0; n < points.size(); ++n) {
    if (!points[n].allFinite()) {
      throw std::invalid_argument("cell grid: point " + std::to_string(n) + " is not finite");
    }
    low = low.cwiseMin(points[n]);
    high = high.cwiseMax(points[n]);
  }
  // floor is monotone: the corners' cells bound every point's (and fail first if too far).
  std::vector<AxisCode> axes;
  for (int a = 0; a < 3; ++a) {
    axes.emplace_back(cell_index(low[a], inverse_cell), cell_index(high[a], inverse_cell));
  }
  if (axes[0].bits() + axes[1].bits() + axes[2].bits() > 64) {
    for (int a = 0; a < 3; ++a) {
      std::vector<int64_t> indices(points.size());
      for (size_t n = 0; n < points.size(); ++n)
        indices[n] = cell_index(points[n][a], inverse_cell);
      axes[static_cast<size_t>(a)] = AxisCode(std::move(indices));
    }
  }
  const int bits_i = axes[0].bits(), bits_j = axes[1].bits(), bits_k = axes[2].bits();
  if (bits_i + bits_j + bits_k > 64) {
    throw std::invalid_argument(
        "cell grid: the points' cells spread over more distinct coordinates than a 64-bit key "
        "holds (" +
        std::to_string(bits_i + bits_j + bits_k) + " bits)");
  }
  shift_j_ = static_cast<uint64_t>(bits_k);
  shift_i_ = static_cast<uint64_t>(bits_j + bits_k);

  std::vector<Entry> entries(points.size());
  for (size_t n = 0; n < points.size(); ++n) {
    const Eigen::Vector3f& p = points[n];
    entries[n] = {axes[0](cell_index(p.x(), inverse_cell)) << shift_i_ |
                      axes[1](cell_index(p.y(), inverse_cell)) << shift_j_ |
                      axes[2](cell_index(p.z(), inverse_cell)),
                  static_cast<uint32_t>(n)};
  }
  radix_sort(&entries, bits_i + bits_j + bits_k);

  x_.resize(points.size());
  y_.resize(points.size());
  z_.resize(points.size());
  input_index_.resize(points.size());
  for (size_t i = 0; i < entries.size(); ++i) {
    if (i > 0 && entries[i].key != entries[i - 1].key) {
      cell_begin_.push_back(static_cast<uint32_t>(i));
    }
    if (i == 0 || entries[i].key != entries[i - 1].key) cell_key_.push_back(entries[i].key);
    const Eigen::Vector3f& p = points[entries[i].index];
    x_[i] = p.x();
    y_[i] = p.y();
    z_[i] = p.z();
    input_index_[i] = entries[i].index;
  }
  cell_begin_.push_back(static_cast<uint32_t>(entries.size()));
}

void CellGrid::block_around(size_t c, std::vector<uint32_t>* cells) const {
  BlockFinder(*this).block_around(c, cells);
}

void CellGrid::BlockFinder::block_around(size_t c, std::vector<uint32_t>* cells) {
  const std::vector<uint64_t>& keys = grid_->cell_key_;
  const bool restart = !started_ || c < last_;
  started_ = true;
  last_ = c;
  cells->clear();
  size_t column = 0;
  for (int64_t di = -1; di <= 1; ++di) {
    for (int64_t dj = -1; dj <= 1; ++dj, ++column) {
      // Key of (i + di, j + dj, k - 1); the run ends at k + 1. Unsigned wrap-around adds the
      // negative offsets; the codes' free margins keep every field in range.
      const uint64_t first = keys[c] + (static_cast<uint64_t>(di) << grid_->shift_i_) +
                             (static_cast<uint64_t>(dj) << grid_->shift_j_) - 1;
      size_t& p = column_[column];
      if (restart) {
        p = static_cast<size_t>(std::lower_bound(keys.begin(), keys.end(), first) - keys.begin());
      } else {
        while (p < keys.size() && keys[p] < first) ++p;
      }
      for (size_t q = p; q < keys.size() && keys[q] <= first + 2; ++q) {
        cells->push_back(static_cast<uint32_t>(q));
      }
    }
  }
}

}  // namespace keel::mapping
