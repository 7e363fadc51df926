// Files keel-server keeps in its data directory besides the store: the first API token
// (<data-dir>/token, mode 0600) and the URL it listens on (<data-dir>/server.url).
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <filesystem>
#include <string>

#include "storage/store.h"

namespace keel::server {

// Writes `content` to a temporary file in the same folder (created with `mode`), fsyncs it
// and renames it over `path`, so readers see the old file or the new one, never a part.
void write_file_atomically(const std::filesystem::path& path, const std::string& content,
                           mode_t mode = 0644);

// 32 random bytes (OpenSSL RAND_bytes) as 64 hex digits.
std::string random_token();

// When the store has no token yet: makes one, stores it (hashed) and writes it to
// <data_dir>/token with mode 0600. Returns true when it made one.
bool ensure_initial_token(storage::Store& store, const std::filesystem::path& data_dir);

// The token the server's local workers (--workers N) use: a worker token of every project
// kept in <data_dir>/worker-token (mode 0600). Reused while the store still accepts it as a
// worker token; otherwise (first start, revoked, expired) a new one is made. Returns the file.
std::filesystem::path ensure_worker_token(storage::Store& store,
                                          const std::filesystem::path& data_dir);

// Bytes free for an unprivileged writer on the filesystem holding `folder` (statvfs); -1 when
// it cannot be read.
int64_t free_bytes_at(const std::filesystem::path& folder);

// Removes temporary files a crash left in the data folder's root (write_file_atomically's
// "<name>.tmp.<pid>"); the store clears its own (blobs' tmp/, uploads without a row).
// Returns how many it removed.
int remove_stale_temp_files(const std::filesystem::path& data_dir);

struct ListenAddress {
  std::string host;
  uint16_t port = 0;
};
// "127.0.0.1:8080", "[::1]:0", "0.0.0.0:80"; std::invalid_argument naming what is wrong.
ListenAddress parse_listen_address(const std::string& text);

}  // namespace keel::server
