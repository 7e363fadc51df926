#include "worker/pipeline/bundle_unpack.h"

#include <archive.h>
#include <archive_entry.h>

#include <memory>
#include <set>
#include <string>
#include <system_error>
#include <vector>

#include "core/tar_path.h"

namespace keel::pipeline {

namespace fs = std::filesystem;

namespace {

struct ReadCloser {
  void operator()(archive* a) const { archive_read_free(a); }
};
struct WriteCloser {
  void operator()(archive* a) const { archive_write_free(a); }
};

std::string archive_message(archive* a) {
  const char* text = archive_error_string(a);
  return text ? text : "unknown libarchive error";
}

// True when `inner` is `outer` or below it (both canonical, component-wise).
bool is_within(const fs::path& inner, const fs::path& outer) {
  auto i = inner.begin();
  for (auto o = outer.begin(); o != outer.end(); ++o, ++i) {
    if (o->empty()) continue;  // trailing separator
    if (i == inner.end() || *i != *o) return false;
  }
  return true;
}

class Unpacker {
 public:
  Unpacker(const fs::path& tar_file, const fs::path& root, const UnpackLimits& limits)
      : tar_file_(tar_file), root_(root), limits_(limits) {}

  void run() {
    open_reader();
    open_writer();
    while (true) {
      archive_entry* entry = nullptr;
      const int status = archive_read_next_header(reader_.get(), &entry);
      if (status == ARCHIVE_EOF) break;
      if (status < ARCHIVE_WARN)
        fail(after_last() + "not a readable tar: " + archive_message(reader_.get()));
      extract(entry);
    }
    if (entries_ == 0) fail("the tar holds no members");
    check_symlinks();
  }

 private:
  [[noreturn]] void fail(const std::string& message) const {
    throw BundleError(tar_file_.string() + ": " + message);
  }
  [[noreturn]] void fail_member(const std::string& member, const std::string& message) const {
    fail("member '" + member + "': " + message);
  }
  std::string after_last() const {
    return last_member_.empty() ? "" : "after member '" + last_member_ + "': ";
  }

  void open_reader() {
    reader_.reset(archive_read_new());
    archive_read_support_format_tar(reader_.get());
    archive_read_support_filter_all(reader_.get());
    if (archive_read_open_filename(reader_.get(), tar_file_.c_str(), 1 << 20) != ARCHIVE_OK)
      fail("cannot open: " + archive_message(reader_.get()));
  }

  void open_writer() {
    writer_.reset(archive_write_disk_new());
    // Never write through a symlink or to a ".." path (defence in depth: names are checked
    // before they reach the writer). Owners and special mode bits are not restored.
    archive_write_disk_set_options(writer_.get(), ARCHIVE_EXTRACT_SECURE_SYMLINKS |
                                                      ARCHIVE_EXTRACT_SECURE_NODOTDOT |
                                                      ARCHIVE_EXTRACT_TIME);
  }

  // The member's path relative to the root, or "" for the root itself ("./").
  std::string relative_name(archive_entry* entry) {
    const char* raw = archive_entry_pathname(entry);
    if (!raw) raw = archive_entry_pathname_utf8(entry);
    if (!raw) fail(after_last() + "a member name cannot be decoded");
    const std::string name(raw);
    if (name.empty()) fail_member(name, "empty member name");
    if (name.front() == '/') fail_member(name, "absolute path not allowed");
    const auto parts = tar_path_components(name);
    if (has_parent_component(parts))
      fail_member(name, "'..' component not allowed (path leaves the bundle)");
    return join_tar_path(parts);
  }

  // A symlink's text, resolved lexically from the member's folder, must stay inside.
  void check_symlink_text(const std::string& member, const std::string& rel, const char* target) {
    if (!target || !*target) fail_member(member, "symbolic link with an empty target");
    const std::string text(target);
    if (text.front() == '/')
      fail_member(member, "symbolic link to absolute path '" + text + "' not allowed");
    auto parts = tar_path_components(rel);
    parts.pop_back();  // the link's own name
    for (const auto& part : tar_path_components(text)) {
      if (part != "..") {
        parts.push_back(part);
      } else if (parts.empty()) {
        fail_member(member, "symbolic link to '" + text + "' points outside the bundle");
      } else {
        parts.pop_back();
      }
    }
  }

  void check_limits(const std::string& member, archive_entry* entry) {
    if (++entries_ > limits_.max_entries)
      fail_member(member, "too many members (limit " + std::to_string(limits_.max_entries) + ")");
    if (archive_entry_size_is_set(entry) && archive_entry_size(entry) > 0 &&
        archive_entry_size(entry) > limits_.max_total_bytes - bytes_)
      fail_member(member, "unpacked size exceeds the limit of " +
                              std::to_string(limits_.max_total_bytes) + " bytes");
  }

  void extract(archive_entry* entry) {
    const std::string member = archive_entry_pathname(entry) ? archive_entry_pathname(entry) : "";
    const std::string rel = relative_name(entry);
    last_member_ = member;
    check_limits(member, entry);

    const char* hardlink = archive_entry_hardlink(entry);
    const mode_t type = archive_entry_filetype(entry);
    if (hardlink) {
      const std::string target(hardlink);
      if (target.empty() || target.front() == '/')
        fail_member(member, "hard link to absolute path '" + target + "' not allowed");
      const auto parts = tar_path_components(target);
      if (has_parent_component(parts))
        fail_member(member, "hard link to '" + target + "' leaves the bundle");
      if (!regular_files_.count(join_tar_path(parts)))
        fail_member(member, "hard link to '" + target + "', which is not an earlier file member");
      archive_entry_set_hardlink(entry, (root_ / join_tar_path(parts)).c_str());
    } else if (type == AE_IFLNK) {
      if (rel.empty()) fail_member(member, "the bundle root cannot be a symbolic link");
      check_symlink_text(member, rel, archive_entry_symlink(entry));
    } else if (type == AE_IFDIR) {
      if (rel.empty()) return;  // "./": the root itself
      archive_entry_set_perm(entry, 0755);
    } else if (type == AE_IFREG) {
      if (rel.empty()) fail_member(member, "a file member needs a name");
      archive_entry_set_perm(entry, (archive_entry_perm(entry) & 0111) ? 0755 : 0644);
    } else {
      const char* kind = type == AE_IFCHR || type == AE_IFBLK ? "device file"
                         : type == AE_IFIFO                   ? "FIFO"
                         : type == AE_IFSOCK                  ? "socket"
                                                              : "special file";
      fail_member(member, std::string(kind) + " not allowed");
    }

    archive_entry_set_pathname(entry, (root_ / rel).c_str());
    if (archive_write_header(writer_.get(), entry) < ARCHIVE_WARN)
      fail_member(member, "cannot extract: " + archive_message(writer_.get()));
    if (!hardlink && type == AE_IFREG) copy_data(member);
    if (archive_write_finish_entry(writer_.get()) < ARCHIVE_WARN)
      fail_member(member, "cannot extract: " + archive_message(writer_.get()));

    if (type == AE_IFLNK && !hardlink) symlinks_.push_back({member, rel});
    if (type == AE_IFREG || hardlink) regular_files_.insert(rel);
  }

  void copy_data(const std::string& member) {
    const void* block = nullptr;
    size_t size = 0;
    la_int64_t offset = 0;
    while (true) {
      const int status = archive_read_data_block(reader_.get(), &block, &size, &offset);
      if (status == ARCHIVE_EOF) return;
      if (status < ARCHIVE_WARN)
        fail_member(member, "truncated or corrupt data: " + archive_message(reader_.get()));
      bytes_ += static_cast<int64_t>(size);
      if (bytes_ > limits_.max_total_bytes)
        fail_member(member, "unpacked size exceeds the limit of " +
                                std::to_string(limits_.max_total_bytes) + " bytes");
      if (archive_write_data_block(writer_.get(), block, size, offset) < ARCHIVE_WARN)
        fail_member(member, "cannot write: " + archive_message(writer_.get()));
    }
  }

  // After extraction, every link must resolve inside the root, following chains of links
  // that a per-link text check cannot see (a -> "sub/.." where sub -> ".").
  void check_symlinks() const {
    for (const auto& [member, rel] : symlinks_) {
      std::error_code ec;
      const fs::path resolved = fs::weakly_canonical(root_ / rel, ec);
      if (ec) fail_member(member, "symbolic link cannot be resolved: " + ec.message());
      if (!is_within(resolved, root_))
        fail_member(member,
                    "symbolic link resolves outside the bundle (" + resolved.string() + ")");
    }
  }

  struct Link {
    std::string member;
    std::string rel;
  };

  fs::path tar_file_;
  fs::path root_;
  UnpackLimits limits_;
  std::unique_ptr<archive, ReadCloser> reader_;
  std::unique_ptr<archive, WriteCloser> writer_;
  int64_t entries_ = 0;
  int64_t bytes_ = 0;
  std::string last_member_;
  std::set<std::string> regular_files_;
  std::vector<Link> symlinks_;
};

}  // namespace

fs::path find_mission_root(const fs::path& folder) {
  std::error_code ec;
  if (fs::is_regular_file(folder / "mission.yaml", ec)) return folder;
  std::vector<fs::path> top;
  for (const auto& item : fs::directory_iterator(folder, ec)) top.push_back(item.path());
  if (top.size() == 1 && !fs::is_symlink(top.front(), ec) && fs::is_directory(top.front(), ec) &&
      fs::is_regular_file(top.front() / "mission.yaml", ec))
    return top.front();
  throw BundleError(folder.string() +
                    ": no mission.yaml at the top level or in a single top folder");
}

fs::path unpack_bundle(const fs::path& tar_file, const fs::path& destination,
                       const UnpackLimits& limits) {
  std::error_code ec;
  if (fs::exists(destination, ec) && !fs::is_empty(destination, ec))
    throw BundleError(tar_file.string() + ": destination " + destination.string() +
                      " is not empty");
  fs::create_directories(destination, ec);
  if (ec)
    throw BundleError(tar_file.string() + ": cannot create " + destination.string() + ": " +
                      ec.message());
  const fs::path root = fs::canonical(destination, ec);
  if (ec) throw BundleError(destination.string() + ": " + ec.message());
  try {
    Unpacker(tar_file, root, limits).run();
    try {
      return find_mission_root(root);
    } catch (const BundleError&) {
      throw BundleError(tar_file.string() +
                        ": no mission.yaml at the top level or in a single top folder");
    }
  } catch (...) {
    fs::remove_all(root, ec);  // never follows links: removes only what was extracted
    throw;
  }
}

}  // namespace keel::pipeline
