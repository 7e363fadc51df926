#include "server/bundle_check.h"

#include <archive.h>
#include <archive_entry.h>

#include <memory>
#include <optional>
#include <set>
#include <vector>

#include "core/tar_path.h"

namespace keel::server {

namespace {

using ArchivePtr = std::unique_ptr<archive, decltype(&archive_read_free)>;

// The member's normalized relative components; throws unsafe_path for '/' or '..'.
std::vector<std::string> safe_components(const std::string& name, const std::string& what) {
  if (!name.empty() && name.front() == '/')
    throw BundleError("unsafe_path", what + " '" + name + "' is an absolute path");
  std::vector<std::string> parts = tar_path_components(name);
  if (has_parent_component(parts))
    throw BundleError("unsafe_path", what + " '" + name + "' has a '..' component");
  return parts;
}

// A symlink at `link_parts` pointing at `target` must resolve inside the bundle (see header).
void check_symlink_target(const std::string& member, const std::vector<std::string>& link_parts,
                          const std::string& target) {
  const std::string what = "member '" + member + "': symlink target '" + target + "'";
  if (target.empty()) throw BundleError("bad_bundle", what + " is empty");
  if (target.front() == '/') throw BundleError("unsafe_path", what + " is absolute");
  std::vector<std::string> parts = tar_path_components(target);
  size_t depth = link_parts.empty() ? 0 : link_parts.size() - 1;  // folder holding the link
  bool seen_normal = false;
  for (const auto& part : parts) {
    if (part == "..") {
      if (seen_normal) throw BundleError("unsafe_path", what + " has '..' after a folder name");
      if (depth == 0) throw BundleError("unsafe_path", what + " leaves the bundle");
      --depth;
    } else {
      seen_normal = true;
    }
  }
}

struct Member {
  std::string name;
  std::vector<std::string> parts;
};

}  // namespace

BundleSummary check_mission_bundle(const std::filesystem::path& tar_file,
                                   const BundleLimits& limits) {
  std::error_code size_error;
  const auto tar_bytes = static_cast<int64_t>(std::filesystem::file_size(tar_file, size_error));
  if (size_error) throw BundleError("bad_bundle", "bundle cannot be read: " + size_error.message());
  const double max_file_bytes = limits.max_sparse_ratio * static_cast<double>(tar_bytes);
  ArchivePtr reader(archive_read_new(), &archive_read_free);
  if (!reader) throw std::runtime_error("libarchive: out of memory");
  archive_read_support_format_tar(reader.get());  // ustar, GNU and pax; no compression
  if (archive_read_open_filename(reader.get(), tar_file.c_str(), 1 << 16) != ARCHIVE_OK)
    throw BundleError("bad_bundle", std::string("bundle is not a readable tar: ") +
                                        archive_error_string(reader.get()));

  BundleSummary summary;
  std::vector<Member> members;
  std::set<std::string> symlinks;
  bool has_manifest = false;
  archive_entry* entry = nullptr;
  for (;;) {
    int status = archive_read_next_header(reader.get(), &entry);
    if (status == ARCHIVE_EOF) break;
    if (status < ARCHIVE_WARN) {
      const char* error = archive_error_string(reader.get());
      throw BundleError("bad_bundle", "bundle is not a valid tar after " +
                                          std::to_string(summary.members) +
                                          " members: " + (error ? error : "unknown error"));
    }
    if (++summary.members > limits.max_members)
      throw BundleError("bad_bundle", "bundle has more than " + std::to_string(limits.max_members) +
                                          " members (the limit)");
    const char* raw_name = archive_entry_pathname(entry);
    std::string name = raw_name ? raw_name : "";
    if (name.empty())
      throw BundleError("bad_bundle",
                        "member #" + std::to_string(summary.members) + " has no name");
    std::vector<std::string> parts = safe_components(name, "member");
    if (static_cast<int>(parts.size()) > limits.max_depth)
      throw BundleError("bad_bundle", "member '" + name.substr(0, 200) + "...' is nested " +
                                          std::to_string(parts.size()) + " folders deep (limit " +
                                          std::to_string(limits.max_depth) + ")");
    const mode_t type = archive_entry_filetype(entry);
    const char* hardlink = archive_entry_hardlink(entry);

    if (hardlink) {
      safe_components(hardlink, "member '" + name + "': hardlink target");
    } else if (type == AE_IFLNK) {
      const char* target = archive_entry_symlink(entry);
      check_symlink_target(name, parts, target ? target : "");
      symlinks.insert(join_tar_path(parts, parts.size()));
    } else if (type == AE_IFREG) {
      summary.file_bytes += archive_entry_size(entry);
      if (static_cast<double>(summary.file_bytes) > max_file_bytes)
        throw BundleError("bad_bundle",
                          "member '" + name + "' makes the files add up to " +
                              std::to_string(summary.file_bytes) + " bytes, more than the " +
                              std::to_string(tar_bytes) +
                              "-byte bundle holds (a sparse member that would unpack to "
                              "more than was sent)");
    } else if (type != AE_IFDIR) {
      throw BundleError("bad_bundle",
                        "member '" + name + "': only files, folders and links are allowed");
    }
    if (parts.size() == 1 && parts[0] == "mission.yaml") {
      if (type != AE_IFREG || hardlink)
        throw BundleError("bad_bundle", "member '" + name + "' must be a regular file");
      has_manifest = true;
    }
    members.push_back({name, std::move(parts)});
    if (hardlink) {
      // A hardlink's target may not pass through a symlink either.
      members.push_back({name, tar_path_components(hardlink)});
    }

    // Reading the data (rather than trusting the header) catches a truncated tar here.
    if (archive_read_data_skip(reader.get()) != ARCHIVE_OK) {
      const char* error = archive_error_string(reader.get());
      throw BundleError("bad_bundle",
                        "member '" + name + "' is truncated: " + (error ? error : "unknown error"));
    }
  }

  // Unpacking a member below a symlink would write through it, wherever it points.
  for (const auto& member : members) {
    for (size_t count = 1; count < member.parts.size(); ++count) {
      std::string prefix = join_tar_path(member.parts, count);
      if (symlinks.count(prefix))
        throw BundleError("unsafe_path",
                          "member '" + member.name + "' lies under the symlink '" + prefix + "'");
    }
  }
  if (!has_manifest)
    throw BundleError("bad_bundle", "bundle has no mission.yaml at its root (" +
                                        std::to_string(summary.members) + " members read)");
  return summary;
}

}  // namespace keel::server
