#include "server/tar_index.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <list>
#include <mutex>

namespace keel::server {
namespace {

constexpr uint64_t kBlock = 512;
constexpr size_t kCacheEntries = 32;

// An octal field (digits, then NUL or spaces); nullopt-like -1 for anything else (base-256
// sizes of members over 8 GiB included).
int64_t octal_field(const char* field, size_t width) {
  size_t k = 0;
  while (k < width && field[k] == ' ') ++k;
  int64_t value = 0;
  size_t digits = 0;
  for (; k < width && field[k] >= '0' && field[k] <= '7'; ++k, ++digits) {
    if (value > (INT64_MAX >> 3)) return -1;
    value = value * 8 + (field[k] - '0');
  }
  for (; k < width; ++k)
    if (field[k] != '\0' && field[k] != ' ') return -1;
  return digits > 0 ? value : -1;
}

std::string c_string(const char* field, size_t width) {
  return std::string(field, strnlen(field, width));
}

class Fd {
 public:
  explicit Fd(const std::filesystem::path& path)
      : fd_(::open(path.c_str(), O_RDONLY | O_CLOEXEC)) {}
  ~Fd() {
    if (fd_ >= 0) ::close(fd_);
  }
  int get() const { return fd_; }

 private:
  int fd_;
};

}  // namespace

TarIndex read_tar_index(const std::filesystem::path& tar, uint64_t size, const std::string& what) {
  const Fd fd(tar);
  if (fd.get() < 0) throw TarIndexError(what + ": cannot open: " + std::strerror(errno));
  TarIndex index;
  std::array<char, kBlock> header{};
  for (uint64_t at = 0;;) {
    if (at + kBlock > size) {
      if (at == size) break;  // no end-of-archive blocks: accepted, as GNU tar does
      throw TarIndexError(what + ": truncated header at byte " + std::to_string(at));
    }
    ssize_t got = 0;
    do got = ::pread(fd.get(), header.data(), kBlock, static_cast<off_t>(at));
    while (got < 0 && errno == EINTR);
    if (got != static_cast<ssize_t>(kBlock))
      throw TarIndexError(what + ": cannot read the header at byte " + std::to_string(at));
    if (std::all_of(header.begin(), header.end(), [](char c) { return c == '\0'; })) break;
    if (std::memcmp(header.data() + 257, "ustar", 5) != 0)
      throw TarIndexError(what + ": the header at byte " + std::to_string(at) +
                          " is not a ustar header");
    // Checksum: the header's bytes with the checksum field counted as spaces.
    int64_t sum = 0;
    for (size_t k = 0; k < kBlock; ++k)
      sum += (k >= 148 && k < 156) ? ' ' : static_cast<unsigned char>(header[k]);
    if (octal_field(header.data() + 148, 8) != sum)
      throw TarIndexError(what + ": bad header checksum at byte " + std::to_string(at));
    const int64_t member_size = octal_field(header.data() + 124, 12);
    if (member_size < 0)
      throw TarIndexError(what + ": bad size field at byte " + std::to_string(at));
    const uint64_t data = at + kBlock;
    const uint64_t bytes = static_cast<uint64_t>(member_size);
    if (bytes > size - data)
      throw TarIndexError(what + ": the member at byte " + std::to_string(at) +
                          " reaches past the end of the file");
    const char type = header[156];
    if (type == 'x' || type == 'g' || type == 'L' || type == 'K')
      throw TarIndexError(what + ": the header at byte " + std::to_string(at) +
                          " uses a pax or GNU extension (not served)");
    if (type == '0' || type == '\0') {
      std::string name = c_string(header.data(), 100);
      const std::string prefix = c_string(header.data() + 345, 155);
      if (!prefix.empty()) name = prefix + "/" + name;
      while (name.rfind("./", 0) == 0) name.erase(0, 2);
      index[name] = TarMember{data, bytes};
    }
    at = data + (bytes + kBlock - 1) / kBlock * kBlock;
  }
  return index;
}

std::shared_ptr<const TarIndex> cached_tar_index(const std::string& sha256,
                                                 const std::filesystem::path& tar, uint64_t size,
                                                 const std::string& what) {
  static std::mutex mutex;
  static std::list<std::pair<std::string, std::shared_ptr<const TarIndex>>> cache;  // newest first
  {
    std::lock_guard<std::mutex> lock(mutex);
    for (auto it = cache.begin(); it != cache.end(); ++it)
      if (it->first == sha256) {
        cache.splice(cache.begin(), cache, it);
        return it->second;
      }
  }
  auto index = std::make_shared<const TarIndex>(read_tar_index(tar, size, what));
  std::lock_guard<std::mutex> lock(mutex);
  cache.emplace_front(sha256, index);
  if (cache.size() > kCacheEntries) cache.pop_back();
  return index;
}

}  // namespace keel::server
