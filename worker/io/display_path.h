// File names in error messages, as the user knows them. A worker runs a job on its own copy
// of the user's mission bundle (<cache>/jobs/<job id>/mission/imu.csv); the user knows
// `imu.csv`, the name inside the bundle they uploaded. Readers name files with
// display_path(), and whoever runs a job on such a copy says where the copy lives with a
// DisplayRoots for as long as the job runs.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace keel::io {

// `path` relative to the innermost DisplayRoots folder that holds it ("imu.csv",
// "lidar_h/scan_0001.pcd"), its file name when it is a root itself (a CAD mesh given apart
// from the bundle); the path as given when no root holds it or none is set.
std::string display_path(const std::filesystem::path& path);

// While alive, display_path() on this thread names files under `roots` relative to them.
// Nests: the previous roots come back when it ends.
class DisplayRoots {
 public:
  explicit DisplayRoots(std::vector<std::filesystem::path> roots);
  ~DisplayRoots();
  DisplayRoots(const DisplayRoots&) = delete;
  DisplayRoots& operator=(const DisplayRoots&) = delete;

 private:
  std::vector<std::filesystem::path> roots_;
  const DisplayRoots* previous_;
  friend std::string display_path(const std::filesystem::path& path);
};

}  // namespace keel::io
