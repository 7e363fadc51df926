// Test helpers for the mesh I/O tests: scratch folders, raw file writing, and comparing
// meshes as sets of oriented triangles (independent of vertex numbering).
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/triangle_mesh.h"
#include "tests/error_of.h"
#include "tests/temp_dir.h"

namespace keel::testing {

// This process's scratch root, removed when the test program exits.
inline const std::filesystem::path& scratch_root() {
  struct Root {
    std::filesystem::path path =
        std::filesystem::temp_directory_path() / ("keel_mesh_" + std::to_string(::getpid()));
    ~Root() {
      std::error_code ignored;
      std::filesystem::remove_all(path, ignored);
    }
  };
  static const Root root;
  return root.path;
}

inline std::filesystem::path scratch_dir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::filesystem::path dir =
      scratch_root() / (std::string(info->test_suite_name()) + "." + info->name());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

template <typename T>
void append_binary(std::string* bytes, T value, bool big_endian = false) {
  char raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  if (big_endian) std::reverse(raw, raw + sizeof(T));
  bytes->append(raw, sizeof(T));
}

using Corner = std::array<double, 3>;
using OrientedTriangle = std::array<Corner, 3>;

// Each face as its corner positions, rotated (orientation kept) so the smallest corner comes
// first; sorted. Equal lists mean the same surface with the same orientation.
inline std::vector<OrientedTriangle> canonical_triangles(const TriangleMesh& mesh) {
  std::vector<OrientedTriangle> triangles;
  for (const auto& f : mesh.faces) {
    OrientedTriangle t;
    for (int c = 0; c < 3; ++c) {
      const Eigen::Vector3d& p = mesh.vertices[f[c]];
      t[c] = {p.x(), p.y(), p.z()};
    }
    const auto first = std::min_element(t.begin(), t.end()) - t.begin();
    std::rotate(t.begin(), t.begin() + first, t.end());
    triangles.push_back(t);
  }
  std::sort(triangles.begin(), triangles.end());
  return triangles;
}

}  // namespace keel::testing
