#include "client/bundle_tar.h"

#include <archive.h>
#include <archive_entry.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <memory>

#include "core/sha256.h"

namespace keel::client {

namespace fs = std::filesystem;

namespace {

constexpr size_t kCopyBufferBytes = 1 << 20;

bool is_inside(const fs::path& candidate, const fs::path& root) {
  const auto [root_end, ignored] =
      std::mismatch(root.begin(), root.end(), candidate.begin(), candidate.end());
  return root_end == root.end();
}

bool is_executable(fs::perms perms) {
  return (perms & (fs::perms::owner_exec | fs::perms::group_exec | fs::perms::others_exec)) !=
         fs::perms::none;
}

// Classifies one directory item; follows in-folder file symlinks.
BundleEntry make_entry(const fs::directory_entry& item, const fs::path& root) {
  BundleEntry entry;
  entry.name = item.path().lexically_relative(root).generic_string();
  entry.source = item.path();
  std::error_code ec;
  if (item.is_symlink(ec)) {
    const fs::path target = fs::weakly_canonical(item.path(), ec);
    if (ec || !is_inside(target, root))
      throw LocalFileError(item.path().string() + ": symlink points outside the mission folder (" +
                           fs::read_symlink(item.path(), ec).string() +
                           "); copy the file in instead");
    if (fs::is_directory(target, ec))
      throw LocalFileError(
          item.path().string() +
          ": symlinked folders are not archived; replace the link with the folder");
    if (!fs::is_regular_file(target, ec))
      throw LocalFileError(item.path().string() + ": symlink to a missing or special file");
    entry.source = target;
  } else if (item.is_directory(ec)) {
    entry.is_directory = true;
    return entry;
  } else if (!item.is_regular_file(ec)) {
    throw LocalFileError(item.path().string() +
                         ": not a regular file or folder (only those go into a bundle)");
  }
  const fs::file_status status = fs::status(entry.source, ec);
  if (ec) throw LocalFileError(entry.source.string() + ": cannot stat: " + ec.message());
  entry.executable = is_executable(status.permissions());
  const auto size = fs::file_size(entry.source, ec);
  if (ec) throw LocalFileError(entry.source.string() + ": cannot read size: " + ec.message());
  entry.size = static_cast<int64_t>(size);
  return entry;
}

struct ArchiveDeleter {
  void operator()(archive* a) const { archive_write_free(a); }
};
struct EntryDeleter {
  void operator()(archive_entry* e) const { archive_entry_free(e); }
};

void check(int rc, archive* a, const fs::path& tar_file) {
  if (rc != ARCHIVE_OK)
    throw LocalFileError(tar_file.string() + ": " +
                         (archive_error_string(a) ? archive_error_string(a) : "libarchive error"));
}

// Streams one file into the archive; its size must match what the header announced.
void copy_file_data(archive* a, const BundleEntry& entry, const fs::path& tar_file) {
  std::ifstream in(entry.source, std::ios::binary);
  if (!in) throw LocalFileError(entry.source.string() + ": cannot open for reading");
  std::vector<char> buffer(kCopyBufferBytes);
  int64_t remaining = entry.size;
  while (remaining > 0) {
    const auto want = static_cast<std::streamsize>(std::min<int64_t>(remaining, buffer.size()));
    in.read(buffer.data(), want);
    if (in.gcount() != want)
      throw LocalFileError(entry.source.string() + ": changed while being archived (short read)");
    if (archive_write_data(a, buffer.data(), static_cast<size_t>(want)) != want)
      check(ARCHIVE_FATAL, a, tar_file);
    remaining -= want;
  }
}

}  // namespace

std::vector<BundleEntry> list_bundle_entries(const fs::path& folder) {
  std::error_code ec;
  if (!fs::is_directory(folder, ec))
    throw LocalFileError(folder.string() + ": not a folder (expected a mission folder)");
  const fs::path root = fs::canonical(folder, ec);
  if (ec) throw LocalFileError(folder.string() + ": " + ec.message());
  std::vector<BundleEntry> entries;
  fs::recursive_directory_iterator it(root, fs::directory_options::none, ec);
  if (ec) throw LocalFileError(folder.string() + ": cannot list: " + ec.message());
  for (const fs::recursive_directory_iterator end; it != end; it.increment(ec)) {
    if (ec) throw LocalFileError(folder.string() + ": cannot list: " + ec.message());
    entries.push_back(make_entry(*it, root));
  }
  if (ec) throw LocalFileError(folder.string() + ": cannot list: " + ec.message());
  std::sort(entries.begin(), entries.end(),
            [](const BundleEntry& a, const BundleEntry& b) { return a.name < b.name; });
  return entries;
}

void write_bundle_tar(const fs::path& folder, const fs::path& tar_file) {
  const std::vector<BundleEntry> entries = list_bundle_entries(folder);
  std::unique_ptr<archive, ArchiveDeleter> a(archive_write_new());
  check(archive_write_set_format_gnutar(a.get()), a.get(), tar_file);
  // 1 MiB writes instead of libarchive's default 10 KiB blocks: a multi-GB bundle is written
  // at disk speed. The tail is still padded to a 512-byte record boundary.
  check(archive_write_set_bytes_per_block(a.get(), 1 << 20), a.get(), tar_file);
  check(archive_write_set_bytes_in_last_block(a.get(), 1), a.get(), tar_file);
  check(archive_write_open_filename(a.get(), tar_file.c_str()), a.get(), tar_file);
  for (const BundleEntry& item : entries) {
    std::unique_ptr<archive_entry, EntryDeleter> entry(archive_entry_new());
    archive_entry_set_pathname(entry.get(), item.name.c_str());
    archive_entry_set_filetype(entry.get(), item.is_directory ? AE_IFDIR : AE_IFREG);
    archive_entry_set_perm(entry.get(), item.is_directory || item.executable ? 0755 : 0644);
    archive_entry_set_size(entry.get(), item.is_directory ? 0 : item.size);
    archive_entry_set_mtime(entry.get(), 0, 0);
    archive_entry_set_uid(entry.get(), 0);
    archive_entry_set_gid(entry.get(), 0);
    check(archive_write_header(a.get(), entry.get()), a.get(), tar_file);
    if (!item.is_directory) copy_file_data(a.get(), item, tar_file);
  }
  check(archive_write_close(a.get()), a.get(), tar_file);
}

fs::path write_bundle_to_cache(const fs::path& folder, const fs::path& cache_dir) {
  std::error_code ec;
  fs::create_directories(cache_dir, ec);
  if (ec)
    throw LocalFileError(cache_dir.string() + ": cannot create cache folder: " + ec.message());
  const fs::path tmp = cache_dir / ("bundle-" + std::to_string(::getpid()) + ".tar.tmp");
  try {
    write_bundle_tar(folder, tmp);
  } catch (...) {
    fs::remove(tmp, ec);
    throw;
  }
  const fs::path final_path = cache_dir / (keel::sha256_file(tmp) + ".tar");
  fs::rename(tmp, final_path, ec);
  if (ec) throw LocalFileError(final_path.string() + ": cannot write: " + ec.message());
  return final_path;
}

}  // namespace keel::client
