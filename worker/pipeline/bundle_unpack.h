// Safe extraction of a mission bundle tar (any format and compression libarchive reads).
//
// A bundle comes from the network, so it is treated as hostile:
//   - member names that are absolute or hold a ".." component are rejected;
//   - symbolic links must resolve inside the target folder (checked on their text when read
//     and again on the extracted tree, which catches chains of links); nothing is ever
//     extracted through a link;
//   - hard links must name an earlier regular-file member;
//   - device files, FIFOs and sockets are rejected;
//   - the entry count and the bytes actually written are capped (decompression bombs).
// Every error names the tar file and the member. On any error the target folder is removed,
// so a failed unpack leaves nothing behind.
#pragma once

#include <cstdint>
#include <filesystem>
#include <stdexcept>

namespace keel::pipeline {

struct UnpackLimits {
  int64_t max_total_bytes = int64_t{256} << 30;  // 256 GiB: larger than any real mission log
  int64_t max_entries = 2'000'000;  // one file per lidar sweep / image: 10^6 is hours of data
};

class BundleError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Extracts `tar_file` into `destination` (created; must not exist or be empty) and returns
// the mission root: `destination` itself when it holds mission.yaml, else its single top
// folder when that holds mission.yaml. Throws BundleError.
std::filesystem::path unpack_bundle(const std::filesystem::path& tar_file,
                                    const std::filesystem::path& destination,
                                    const UnpackLimits& limits = {});

// The mission root inside an already extracted folder (same rule as above).
std::filesystem::path find_mission_root(const std::filesystem::path& folder);

}  // namespace keel::pipeline
