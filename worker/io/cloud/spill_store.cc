#include "worker/io/cloud/spill_store.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace keel::io {
namespace {

int open_anonymous_file(const std::filesystem::path& folder) {
#ifdef O_TMPFILE
  const int fd = ::open(folder.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);
  if (fd >= 0) return fd;
#endif
  // Filesystems without O_TMPFILE: a named file, unlinked at once.
  std::string name = (folder / ".keel-spill-XXXXXX").string();
  const int named = ::mkostemp(name.data(), O_CLOEXEC);
  if (named < 0) return -1;
  ::unlink(name.c_str());
  return named;
}

[[noreturn]] void fail(const std::filesystem::path& folder, const std::string& what, int error) {
  throw std::runtime_error("spill file in " + folder.string() + ": " + what + ": " +
                           std::strerror(error));
}

}  // namespace

size_t StreamKeyHash::operator()(const StreamKey& key) const {
  uint64_t h = (uint64_t{key.cloud} << 16) ^ (uint64_t{key.kind} << 8) ^ key.level;
  h = h * 0x9e3779b97f4a7c15ULL ^ static_cast<uint32_t>(key.x);
  h = h * 0xc2b2ae3d27d4eb4fULL ^ static_cast<uint32_t>(key.y);
  h = h * 0x165667b19e3779f9ULL ^ static_cast<uint32_t>(key.z);
  h ^= h >> 32;
  h *= 0xd6e8feb86659fd93ULL;
  return static_cast<size_t>(h ^ (h >> 32));
}

SpillStore::SpillStore(const std::filesystem::path& folder, size_t buffer_budget_bytes)
    : folder_(folder), budget_(buffer_budget_bytes) {
  fd_ = open_anonymous_file(folder);
  if (fd_ < 0) fail(folder, "cannot create", errno);
}

SpillStore::~SpillStore() {
  if (fd_ >= 0) ::close(fd_);
}

void SpillStore::append(const StreamKey& key, const void* data, size_t bytes) {
  if (bytes == 0) return;
  std::lock_guard<std::mutex> lock(mutex_);
  Stream& stream = streams_[key];
  const size_t before = stream.buffer.capacity();
  const char* begin = static_cast<const char*>(data);
  stream.buffer.insert(stream.buffer.end(), begin, begin + bytes);
  stream.bytes += bytes;
  buffered_ += stream.buffer.capacity() - before;
  peak_buffered_ = std::max(peak_buffered_, buffered_);
  if (buffered_ > budget_) spill_locked();
}

void SpillStore::write_block_locked(Stream& stream) {
  const std::vector<char>& buffer = stream.buffer;
  size_t done = 0;
  while (done < buffer.size()) {
    const ssize_t n = ::pwrite(fd_, buffer.data() + done, buffer.size() - done,
                               static_cast<off_t>(file_end_ + done));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) fail(folder_, "write", n < 0 ? errno : EIO);
    done += static_cast<size_t>(n);
  }
  stream.blocks.push_back(Block{file_end_, buffer.size()});
  file_end_ += buffer.size();
  buffered_ -= buffer.capacity();
  stream.buffer = std::vector<char>();  // releases the memory
}

void SpillStore::spill_locked() {
  std::vector<std::pair<size_t, Stream*>> by_size;
  by_size.reserve(streams_.size());
  for (auto& [key, stream] : streams_)
    if (!stream.buffer.empty()) by_size.emplace_back(stream.buffer.capacity(), &stream);
  std::sort(by_size.begin(), by_size.end(),
            [](const auto& a, const auto& b) { return a.first > b.first; });
  for (const auto& [capacity, stream] : by_size) {
    if (buffered_ <= budget_ / 2) break;
    write_block_locked(*stream);
  }
}

void SpillStore::for_each_piece(const StreamKey& key, size_t max_piece, size_t unit,
                                const std::function<void(const char*, size_t)>& visit) {
  std::vector<Block> blocks;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto found = streams_.find(key);
    if (found == streams_.end()) return;
    if (!found->second.buffer.empty()) write_block_locked(found->second);
    blocks = found->second.blocks;
  }
  const size_t piece = std::max(unit, max_piece / unit * unit);
  std::vector<char> data;
  // Blocks hold whole units (appends are whole records), so pieces never split one.
  for (const Block& block : blocks)
    for (uint64_t start = 0; start < block.bytes; start += piece) {
      const size_t bytes = static_cast<size_t>(std::min<uint64_t>(piece, block.bytes - start));
      data.resize(bytes);
      size_t done = 0;
      while (done < bytes) {
        const ssize_t n = ::pread(fd_, data.data() + done, bytes - done,
                                  static_cast<off_t>(block.offset + start + done));
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) fail(folder_, "read", n < 0 ? errno : EIO);
        done += static_cast<size_t>(n);
      }
      visit(data.data(), bytes);
    }
}

uint64_t SpillStore::size(const StreamKey& key) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto found = streams_.find(key);
  return found == streams_.end() ? 0 : found->second.bytes;
}

std::string SpillStore::read(const StreamKey& key) const {
  std::vector<Block> blocks;
  std::string out;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto found = streams_.find(key);
    if (found == streams_.end()) return out;
    blocks = found->second.blocks;
    out.resize(found->second.bytes);
    const std::vector<char>& buffer = found->second.buffer;
    if (!buffer.empty())  // memcpy's pointers must not be null, even for 0 bytes
      std::memcpy(out.data() + (out.size() - buffer.size()), buffer.data(), buffer.size());
  }
  // Spilled blocks are immutable once listed: read them without the lock.
  size_t at = 0;
  for (const Block& block : blocks) {
    size_t done = 0;
    while (done < block.bytes) {
      const ssize_t n = ::pread(fd_, out.data() + at + done, block.bytes - done,
                                static_cast<off_t>(block.offset + done));
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) fail(folder_, "read", n < 0 ? errno : EIO);
      done += static_cast<size_t>(n);
    }
    at += block.bytes;
  }
  return out;
}

void SpillStore::erase(const StreamKey& key) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto found = streams_.find(key);
  if (found == streams_.end()) return;
  buffered_ -= found->second.buffer.capacity();
  streams_.erase(found);
}

std::vector<StreamKey> SpillStore::keys(uint16_t cloud, uint8_t kind) const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<StreamKey> keys;
  for (const auto& [key, stream] : streams_)
    if (key.cloud == cloud && key.kind == kind) keys.push_back(key);
  return keys;
}

uint64_t SpillStore::bytes_spilled() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return file_end_;
}

uint64_t SpillStore::bytes_buffered() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return buffered_;
}

uint64_t SpillStore::peak_bytes_buffered() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return peak_buffered_;
}

}  // namespace keel::io
