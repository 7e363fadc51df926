// Builds tar files in memory with libarchive for the server tests, including hostile ones
// (absolute names, '..', symlinks that leave the bundle, device nodes).
#pragma once

#include <archive.h>
#include <archive_entry.h>

#include <stdexcept>
#include <string>
#include <vector>

namespace keel::server::testing {

struct TarMember {
  enum class Kind { kFile, kDir, kSymlink, kHardlink, kCharDevice };
  std::string name;
  Kind kind = Kind::kFile;
  std::string content;  // file bytes, or the link target
};

inline TarMember tar_file(std::string name, std::string content) {
  return {std::move(name), TarMember::Kind::kFile, std::move(content)};
}
inline TarMember tar_dir(std::string name) { return {std::move(name), TarMember::Kind::kDir, ""}; }
inline TarMember tar_symlink(std::string name, std::string target) {
  return {std::move(name), TarMember::Kind::kSymlink, std::move(target)};
}
inline TarMember tar_hardlink(std::string name, std::string target) {
  return {std::move(name), TarMember::Kind::kHardlink, std::move(target)};
}

// format: ARCHIVE_FORMAT_TAR_USTAR, ARCHIVE_FORMAT_TAR_GNUTAR or ARCHIVE_FORMAT_TAR_PAX_RESTRICTED.
inline std::string build_tar(const std::vector<TarMember>& members, bool gzip = false,
                             int format = ARCHIVE_FORMAT_TAR_PAX_RESTRICTED) {
  archive* writer = archive_write_new();
  archive_write_set_format(writer, format);
  if (gzip) archive_write_add_filter_gzip(writer);
  archive_write_set_bytes_in_last_block(writer, 1);
  std::vector<char> buffer(16 << 20);
  size_t used = 0;
  if (archive_write_open_memory(writer, buffer.data(), buffer.size(), &used) != ARCHIVE_OK)
    throw std::runtime_error(archive_error_string(writer));
  for (const auto& member : members) {
    archive_entry* entry = archive_entry_new();
    archive_entry_set_pathname(entry, member.name.c_str());
    archive_entry_set_perm(entry, 0644);
    switch (member.kind) {
      case TarMember::Kind::kFile:
        archive_entry_set_filetype(entry, AE_IFREG);
        archive_entry_set_size(entry, static_cast<la_int64_t>(member.content.size()));
        break;
      case TarMember::Kind::kDir:
        archive_entry_set_filetype(entry, AE_IFDIR);
        archive_entry_set_perm(entry, 0755);
        break;
      case TarMember::Kind::kSymlink:
        archive_entry_set_filetype(entry, AE_IFLNK);
        archive_entry_set_symlink(entry, member.content.c_str());
        break;
      case TarMember::Kind::kHardlink:
        archive_entry_set_filetype(entry, AE_IFREG);
        archive_entry_set_hardlink(entry, member.content.c_str());
        break;
      case TarMember::Kind::kCharDevice:
        archive_entry_set_filetype(entry, AE_IFCHR);
        archive_entry_set_rdev(entry, 0x0103);
        break;
    }
    if (archive_write_header(writer, entry) != ARCHIVE_OK)
      throw std::runtime_error(std::string("tar header: ") + archive_error_string(writer));
    if (member.kind == TarMember::Kind::kFile && !member.content.empty())
      archive_write_data(writer, member.content.data(), member.content.size());
    archive_entry_free(entry);
  }
  archive_write_close(writer);
  archive_write_free(writer);
  return std::string(buffer.data(), used);
}

inline std::string minimal_manifest(const std::string& name = "usv-test") {
  return "keel_mission: 1\nname: " + name + "\n";
}

// A small valid bundle: mission.yaml at the root plus a data folder.
inline std::string valid_bundle(const std::string& name = "usv-test") {
  return build_tar({tar_file("mission.yaml", minimal_manifest(name)), tar_dir("data"),
                    tar_file("data/imu.csv", "t,ax,ay,az\n0.0,0,0,9.81\n")});
}

}  // namespace keel::server::testing
