// Out-of-core byte streams for the map stage's tiles (issue 17): bytes are appended to keyed
// streams and kept in memory while the buffered total stays within a budget; above it, the
// largest buffers are written to one backing file as blocks, until half the budget is
// buffered. Reading a stream gives its bytes in append order, from its blocks and its buffer.
//
// The backing file is anonymous (O_TMPFILE in the given folder, else created and unlinked at
// once): it never outlives the process, even one that crashes.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

namespace keel::io {

// Which stream: a cloud (the caller's number), a kind (e.g. a tile's core or halo) and a tile
// (level and integer coordinates).
struct StreamKey {
  uint16_t cloud = 0;
  uint8_t kind = 0;
  uint8_t level = 0;
  int32_t x = 0, y = 0, z = 0;
  bool operator==(const StreamKey& o) const {
    return cloud == o.cloud && kind == o.kind && level == o.level && x == o.x && y == o.y &&
           z == o.z;
  }
};

struct StreamKeyHash {
  size_t operator()(const StreamKey& key) const;
};

class SpillStore {
 public:
  // Throws std::runtime_error naming `folder` when the backing file cannot be made.
  SpillStore(const std::filesystem::path& folder, size_t buffer_budget_bytes);
  ~SpillStore();
  SpillStore(const SpillStore&) = delete;
  SpillStore& operator=(const SpillStore&) = delete;

  // Appends to a stream (made on first use). Thread-safe. Throws std::runtime_error naming the
  // folder when a spill write fails (a full disk).
  void append(const StreamKey& key, const void* data, size_t bytes);
  // Bytes of a stream (0 for none). Thread-safe.
  uint64_t size(const StreamKey& key) const;
  // The stream's bytes in append order (empty for none). Thread-safe, also beside appends to
  // other streams.
  std::string read(const StreamKey& key) const;
  // The stream's bytes in append order, in pieces of at most `max_piece` bytes (rounded down to
  // whole `unit`s), so a large stream is read with little memory: its buffer is written out
  // first. Appends to the stream must not overlap it.
  void for_each_piece(const StreamKey& key, size_t max_piece, size_t unit,
                      const std::function<void(const char* data, size_t bytes)>& visit);
  // Forgets a stream: its buffer's memory goes now, its spilled bytes with the store.
  void erase(const StreamKey& key);
  // The keys of `cloud`'s streams of `kind`, in no particular order.
  std::vector<StreamKey> keys(uint16_t cloud, uint8_t kind) const;

  uint64_t bytes_spilled() const;   // written to the backing file so far
  uint64_t bytes_buffered() const;  // held in memory now
  uint64_t peak_bytes_buffered() const;
  size_t buffer_budget() const { return budget_; }

 private:
  struct Block {
    uint64_t offset = 0, bytes = 0;
  };
  struct Stream {
    std::vector<Block> blocks;  // spilled, in order
    std::vector<char> buffer;   // not spilled yet, after the blocks (capacity counted)
    uint64_t bytes = 0;         // blocks + buffer
  };
  // With mutex_ held: writes a stream's buffer as a block.
  void write_block_locked(Stream& stream);
  // With mutex_ held: writes the largest buffers until at most half the budget is buffered.
  void spill_locked();

  std::filesystem::path folder_;
  size_t budget_;
  int fd_ = -1;
  mutable std::mutex mutex_;
  std::unordered_map<StreamKey, Stream, StreamKeyHash> streams_;
  uint64_t file_end_ = 0;
  uint64_t buffered_ = 0;  // sum of buffer capacities
  uint64_t peak_buffered_ = 0;
};

}  // namespace keel::io
