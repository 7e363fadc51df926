#include "worker/compare/cell_sort.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/parallel_for.h"

namespace keel::compare {
namespace {

int bits_for(int64_t largest) {
  int bits = 0;
  while (bits < 63 && (largest >> bits) != 0) ++bits;
  return bits;
}

// Stable LSD radix sort on the low `bits` bits of key_of(entry), 11 bits a pass.
template <typename Entry, typename KeyOf>
void radix_sort(std::vector<Entry>* entries, int bits, const KeyOf& key_of) {
  constexpr int kDigit = 11;
  constexpr size_t kBuckets = size_t{1} << kDigit;
  if (bits <= 0 || entries->size() < 2) return;
  std::vector<Entry> other(entries->size());
  std::vector<size_t> offsets(kBuckets);
  for (int shift = 0; shift < bits; shift += kDigit) {
    std::fill(offsets.begin(), offsets.end(), 0);
    for (const Entry& e : *entries) ++offsets[(key_of(e) >> shift) & (kBuckets - 1)];
    size_t total = 0;
    for (size_t& offset : offsets) total += std::exchange(offset, total);
    for (const Entry& e : *entries) other[offsets[(key_of(e) >> shift) & (kBuckets - 1)]++] = e;
    entries->swap(other);
  }
}

}  // namespace

KeyedIndices::KeyedIndices(size_t n, int key_bits) : key_bits_(key_bits) {
  if (packed())
    words_.resize(n);
  else
    pairs_.resize(n);
}

void KeyedIndices::sort() {
  if (packed())
    radix_sort(&words_, key_bits_, [](uint64_t w) { return w >> 32; });
  else
    radix_sort(&pairs_, key_bits_, [](const std::pair<uint64_t, uint32_t>& e) { return e.first; });
}

std::array<int64_t, 3> CellSort::cell_of_key(uint64_t key) const {
  const uint64_t y_mask = (uint64_t(1) << bits[1]) - 1, z_mask = (uint64_t(1) << bits[2]) - 1;
  return {int64_t(key >> (bits[1] + bits[2])), int64_t((key >> bits[2]) & y_mask),
          int64_t(key & z_mask)};
}

CellSort sort_into_cells(const std::vector<Eigen::Vector3f>& points, double cell_m,
                         const std::string& what, int threads) {
  if (!(cell_m > 0.0) || !std::isfinite(cell_m))
    throw std::invalid_argument(what + ": the cell size must be a positive number of metres");
  CellSort out;
  out.cell_m = cell_m;
  if (points.empty()) return out;
  Eigen::Vector3d lo = points.front().cast<double>(), hi = lo;
  for (const auto& p : points) {
    if (!p.allFinite()) throw std::invalid_argument(what + ": a point is not finite");
    lo = lo.cwiseMin(p.cast<double>());
    hi = hi.cwiseMax(p.cast<double>());
  }
  out.origin = lo;
  const double inv = 1.0 / cell_m;
  // floor is monotone: the highest point's cell bounds every index along each axis.
  constexpr int64_t kMax = (int64_t(1) << kCellAxisBits) - 1;
  for (int axis = 0; axis < 3; ++axis) {
    const double top = std::floor((hi[axis] - lo[axis]) * inv);
    if (top > double(kMax))
      throw std::invalid_argument(what + ": the cloud spans more than 2^21 cells of " +
                                  std::to_string(cell_m) + " m");
    out.bits[axis] = bits_for(int64_t(top));
    out.cells[axis] = int64_t(top) + 1;
  }
  const int shift_x = out.bits[1] + out.bits[2], shift_y = out.bits[2];
  out.keyed = KeyedIndices(points.size(), out.bits[0] + out.bits[1] + out.bits[2]);
  keel::parallel_for(points.size(), threads, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) {
      const Eigen::Vector3d c = (points[i].cast<double>() - lo) * inv;
      const uint64_t x = uint64_t(std::floor(c.x())), y = uint64_t(std::floor(c.y())),
                     z = uint64_t(std::floor(c.z()));
      out.keyed.set(i, x << shift_x | y << shift_y | z, uint32_t(i));
    }
  });
  out.keyed.sort();
  return out;
}

}  // namespace keel::compare
