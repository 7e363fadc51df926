// The content-addressed blob folder: a blob's file is blobs/<first 2 hex>/<sha256>.
// New content is written to a temp file in tmp/, fsynced, renamed into place and the
// directory fsynced, so a blob file is either absent or complete; tmp/ never shares a
// folder with finished blobs. Identical content is stored once.
//
// This class knows files only; the store records blobs (and their sizes) in its database.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

namespace keel::storage {

class BlobStore {
 public:
  // Creates both folders if needed. They must be on one filesystem (rename is atomic).
  BlobStore(std::filesystem::path blobs_dir, std::filesystem::path tmp_dir);

  // Throws std::invalid_argument unless `sha256` is 64 lowercase hex digits.
  std::filesystem::path path_of(const std::string& sha256) const;
  bool contains(const std::string& sha256) const;
  int64_t size_of(const std::string& sha256) const;  // throws std::system_error if absent

  // Stores `bytes` and returns their SHA-256.
  std::string put(const std::string& bytes);
  // Moves `file`, whose content hashes to `sha256` (the caller checked), into the store; if
  // the blob is there already the file is just removed. `file` must be fsynced and on the
  // same filesystem.
  void adopt(const std::filesystem::path& file, const std::string& sha256);

  // A fresh, unused name in tmp/ for a file being written.
  std::filesystem::path temp_path() const;
  // Removes temp files left by writes a crash cut short. Call before any writer starts.
  void clear_tmp();

  const std::filesystem::path& blobs_dir() const { return blobs_dir_; }
  const std::filesystem::path& tmp_dir() const { return tmp_dir_; }

 private:
  // Renames `file` to the blob's path, creating blobs/ab/ (durably) first.
  void move_into_place(const std::filesystem::path& file, const std::string& sha256);

  std::filesystem::path blobs_dir_;
  std::filesystem::path tmp_dir_;
};

}  // namespace keel::storage
