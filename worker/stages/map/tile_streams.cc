#include "worker/stages/map/tile_streams.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

namespace keel::pipeline {
namespace {

// Records per stream batch before it goes to the store (64 KiB).
constexpr size_t kBatchRecords = 4096;
// All batches together before every one is flushed (4 MiB).
constexpr size_t kMaxBatchedRecords = 1 << 18;

// Neighbour boxes a binner keeps in its halo reaches (56 bytes each: 3.5 MiB), however far
// the halos reach (26 neighbours a tile at a reach of one tile, 124 at two).
constexpr size_t kMaxReachNeighbours = size_t{1} << 16;

constexpr float kNoIntensity = std::numeric_limits<float>::quiet_NaN();

}  // namespace

io::StreamKey stream_key(uint16_t cloud, TileStream kind, const mapping::TileKey& tile) {
  return io::StreamKey{cloud, static_cast<uint8_t>(kind), tile.level, tile.x, tile.y, tile.z};
}

mapping::TileKey tile_of_key(const io::StreamKey& key) {
  return mapping::TileKey{key.x, key.y, key.z, key.level};
}

std::vector<PointRecord> read_records(const io::SpillStore& store, const io::StreamKey& key) {
  const std::string bytes = store.read(key);
  if (bytes.size() % sizeof(PointRecord) != 0)
    throw std::logic_error("tile stream of " + std::to_string(bytes.size()) +
                           " bytes is not whole records");
  std::vector<PointRecord> records(bytes.size() / sizeof(PointRecord));
  std::memcpy(records.data(), bytes.data(), bytes.size());
  return records;
}

void append_records(const std::vector<PointRecord>& records, bool with_intensity, PointCloud& out) {
  out.xyz.reserve(out.xyz.size() + records.size());
  for (const PointRecord& r : records) out.xyz.emplace_back(r.x, r.y, r.z);
  if (!with_intensity) return;
  out.intensity.reserve(out.intensity.size() + records.size());
  for (const PointRecord& r : records) out.intensity.push_back(r.intensity);
}

TileBinner::TileBinner(io::SpillStore& store, uint16_t cloud, const mapping::TileGrid& grid,
                       HaloFunction halo, bool has_halo, int level)
    : store_(store),
      cloud_(cloud),
      grid_(grid),
      halo_(std::move(halo)),
      has_halo_(has_halo),
      level_(level) {}

TileBinner::~TileBinner() {
  try {
    flush();
  } catch (...) {  // a destructor must not throw; flush() first to see the error
  }
}

void TileBinner::push(TileStream kind, const mapping::TileKey& tile, const PointRecord& record) {
  std::vector<PointRecord>* batch;
  if (kind == TileStream::kCore && core_batch_ != nullptr && tile == core_tile_) {
    batch = core_batch_;
  } else {
    batch = &batches_[stream_key(cloud_, kind, tile)];  // a node: stays put until erased
    if (kind == TileStream::kCore) core_tile_ = tile, core_batch_ = batch;
  }
  batch->push_back(record);
  ++batched_;
  if (batch->size() >= kBatchRecords) {
    store_.append(stream_key(cloud_, kind, tile), batch->data(),
                  batch->size() * sizeof(PointRecord));
    batched_ -= batch->size();
    batch->clear();
  }
  if (batched_ >= kMaxBatchedRecords) flush();
}

void TileBinner::add(const PointRecord& record) {
  const Eigen::Vector3f p(record.x, record.y, record.z);
  const mapping::TileKey home = grid_.tile_of(p, level_);
  push(TileStream::kCore, home, record);
  if (!has_halo_) return;
  auto reach = reaches_.find(home);
  if (reach == reaches_.end()) {
    mapping::TileGrid::HaloReach made = grid_.halo_reach(home, halo_);
    if (reach_neighbours_ + made.neighbours.size() > kMaxReachNeighbours) {
      reaches_.clear();
      reach_neighbours_ = 0;
    }
    reach_neighbours_ += made.neighbours.size();
    reach = reaches_.emplace(home, std::move(made)).first;
  }
  grid_.for_each_halo_tile(p, reach->second, [&](const mapping::TileKey& other) {
    push(TileStream::kHalo, other, record);
  });
}

void TileBinner::add(const PointCloud& points) {
  const bool with_intensity = points.intensity.size() == points.size();
  for (size_t k = 0; k < points.size(); ++k) {
    const Eigen::Vector3f& p = points.xyz[k];
    add(PointRecord{p.x(), p.y(), p.z(), with_intensity ? points.intensity[k] : kNoIntensity});
  }
}

void TileBinner::flush() {
  for (auto& [key, batch] : batches_) {
    if (batch.empty()) continue;
    store_.append(key, batch.data(), batch.size() * sizeof(PointRecord));
    batch.clear();
  }
  batches_.clear();
  core_batch_ = nullptr;
  batched_ = 0;
}

std::vector<mapping::TileKey> split_tile(io::SpillStore& store, const std::vector<uint16_t>& clouds,
                                         const mapping::TileGrid& grid,
                                         const mapping::TileKey& tile, const HaloFunction& halo,
                                         bool has_halo, bool erase_parent) {
  mapping::TileKey children[8];
  mapping::Box halo_boxes[8];
  for (int c = 0; c < 8; ++c) {
    children[c] = grid.child(tile, c);
    const mapping::Box box = grid.box(children[c]);
    halo_boxes[c] = box.expanded(has_halo ? halo(box) : 0.0);
  }
  // A tile is split because it is too large to read whole: it is read in pieces, and its
  // children's streams are appended in batches.
  constexpr size_t kPieceBytes = 4u << 20;
  std::vector<bool> holds(8, false);
  for (const uint16_t cloud : clouds) {
    std::vector<PointRecord> batches[2][8];  // [core, halo][child]
    const auto put = [&](TileStream kind, int c, const PointRecord& r) {
      std::vector<PointRecord>& batch = batches[static_cast<int>(kind)][c];
      batch.push_back(r);
      if (batch.size() < kBatchRecords) return;
      store.append(stream_key(cloud, kind, children[c]), batch.data(),
                   batch.size() * sizeof(PointRecord));
      batch.clear();
    };
    const auto to_halos = [&](const PointRecord& r, int skip) {
      if (!has_halo) return;
      const Eigen::Vector3d p(r.x, r.y, r.z);
      for (int c = 0; c < 8; ++c)
        if (c != skip && halo_boxes[c].contains(p)) put(TileStream::kHalo, c, r);
    };
    const auto each_record = [&](TileStream kind,
                                 const std::function<void(const PointRecord&)>& f) {
      store.for_each_piece(stream_key(cloud, kind, tile), kPieceBytes, sizeof(PointRecord),
                           [&](const char* data, size_t bytes) {
                             for (size_t at = 0; at < bytes; at += sizeof(PointRecord)) {
                               PointRecord r;
                               std::memcpy(&r, data + at, sizeof(r));
                               f(r);
                             }
                           });
    };
    // The tile's own points first, then its halo: each child's halo keeps that order (a voxel's
    // points come from one tile, so each voxel's points stay in feed order).
    each_record(TileStream::kCore, [&](const PointRecord& r) {
      const mapping::TileKey home = grid.tile_of(Eigen::Vector3f(r.x, r.y, r.z), tile.level + 1);
      int c = 0;
      while (c < 8 && children[c] != home) ++c;
      if (c == 8)
        throw std::logic_error("split_tile: a point of tile " + tile.to_string() +
                               " lies in none of its children");
      holds[c] = true;
      put(TileStream::kCore, c, r);
      to_halos(r, c);
    });
    each_record(TileStream::kHalo, [&](const PointRecord& r) { to_halos(r, -1); });
    if (erase_parent) {
      store.erase(stream_key(cloud, TileStream::kCore, tile));
      store.erase(stream_key(cloud, TileStream::kHalo, tile));
    }
    for (int kind = 0; kind < 2; ++kind)
      for (int c = 0; c < 8; ++c)
        store.append(stream_key(cloud, static_cast<TileStream>(kind), children[c]),
                     batches[kind][c].data(), batches[kind][c].size() * sizeof(PointRecord));
  }
  // (A child's halo without a core of these clouds stays: another cloud may have one there.)
  std::vector<mapping::TileKey> out;
  for (int c = 0; c < 8; ++c)
    if (holds[c]) out.push_back(children[c]);
  return out;
}

}  // namespace keel::pipeline
