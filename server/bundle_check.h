// Checks an uploaded mission bundle before it becomes a mission: it must be a plain tar
// (ustar, GNU or pax) whose members all stay inside the folder it unpacks to, and it must
// hold `mission.yaml` at its root (docs/mission-format.md). `./mission.yaml`, as written by
// `tar -C <folder> -cf bundle.tar .`, counts as the root; a bundle whose only top-level
// entry is a folder does not (the worker unpacks the tar and reads <dir>/mission.yaml).
//
// A member is unsafe when its name is absolute or has a `..` component, when its name
// passes through a symlink member, when a hardlink names an unsafe target, or when a
// symlink's target is absolute or leaves the bundle. To keep the check lexical and sound,
// `..` in a symlink target is allowed only as a leading run (`../x/y`), never after a
// normal component (`x/../y` could climb out through a symlinked `x`).
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>

namespace keel::server {

class BundleError : public std::runtime_error {
 public:
  // code: "unsafe_path" (a member would land outside the bundle) or "bad_bundle".
  BundleError(std::string code, const std::string& message)
      : std::runtime_error(message), code_(std::move(code)) {}
  const std::string& code() const { return code_; }

 private:
  std::string code_;
};

// Bundles built to exhaust the server or a worker (tar bombs) are refused before anything is
// unpacked. A plain tar stores every file byte, so files cannot add up to more than the
// tar's own size, except through sparse members (GNU/pax sparse maps) whose declared size
// costs nothing to send; those are refused when they would unpack to more than
// `max_sparse_ratio` times the tar's size.
struct BundleLimits {
  int max_members = 1'000'000;  // one file per lidar sweep or image: hours of data
  int max_depth = 64;           // folders nested in one member's name
  double max_sparse_ratio = 1.0;
};

struct BundleSummary {
  int members = 0;         // entries in the tar
  int64_t file_bytes = 0;  // sum of regular file sizes
};

// Throws BundleError naming the offending member (or the tar itself).
BundleSummary check_mission_bundle(const std::filesystem::path& tar_file,
                                   const BundleLimits& limits = {});

}  // namespace keel::server
