// Deterministic tar of a mission folder (the bundle blob): the same folder contents give
// the same bytes whatever the file order on disk, mtimes, owners or umask, so a re-run
// submit finds the same blob and resumes its upload.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "client/local_file_error.h"

namespace keel::client {

struct BundleEntry {
  std::string name;              // relative path, '/'-separated; folders end without '/'
  std::filesystem::path source;  // file to read (a symlink's resolved target)
  bool is_directory = false;
  bool executable = false;
  int64_t size = 0;
};

// The entries of `folder`, sorted by name (byte order). Symlinks are followed when they
// point at a regular file inside the folder; a symlink leaving the folder, a symlinked
// folder, or any other file type throws LocalFileError naming it.
std::vector<BundleEntry> list_bundle_entries(const std::filesystem::path& folder);

// Writes the entries of `folder` to `tar_file` as a GNU tar (long names, large files)
// with mtime 0, uid/gid 0, no user/group names, modes 0755 (folders, executables) or 0644.
// Throws LocalFileError naming the file on read/write problems.
void write_bundle_tar(const std::filesystem::path& folder, const std::filesystem::path& tar_file);

// Writes the bundle into `cache_dir` as `<sha256>.tar` (through a temporary file) and
// returns its path; an existing identical tar is reused.
std::filesystem::path write_bundle_to_cache(const std::filesystem::path& folder,
                                            const std::filesystem::path& cache_dir);

}  // namespace keel::client
