// The members of an uncompressed POSIX tar (ustar, as libarchive and GNU tar write it) read from
// its 512-byte headers: each regular file's path, data offset and size, so that one member of
// a folder artifact (the map tiles, docs/artifacts.md) is served as a region of the stored
// file, with Range like any artifact. Indexes are cached by content (the SHA-256 of the tar):
// stored blobs never change.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>

namespace keel::server {

struct TarMember {
  uint64_t offset = 0;  // of the data, in the tar file
  uint64_t size = 0;
};
using TarIndex = std::map<std::string, TarMember>;

// Not a ustar archive, or a header or member reaching past the end of the file: the message
// names the file's description and the header's offset.
class TarIndexError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Reads `tar` (of `size` bytes) header by header. Pax and GNU extension headers are refused
// (Keel writes none). `what` names the tar in errors.
TarIndex read_tar_index(const std::filesystem::path& tar, uint64_t size, const std::string& what);

// read_tar_index through a small cache keyed by `sha256` (thread-safe).
std::shared_ptr<const TarIndex> cached_tar_index(const std::string& sha256,
                                                 const std::filesystem::path& tar, uint64_t size,
                                                 const std::string& what);

}  // namespace keel::server
