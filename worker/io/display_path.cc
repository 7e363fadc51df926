#include "worker/io/display_path.h"

namespace keel::io {

namespace fs = std::filesystem;

namespace {

// The roots of the job this thread runs (one job per thread: the job runner's).
thread_local const DisplayRoots* current_roots = nullptr;

// `path` below `root` (both lexically normal): the rest, else empty.
fs::path below(const fs::path& path, const fs::path& root) {
  auto p = path.begin();
  for (auto r = root.begin(); r != root.end(); ++r, ++p) {
    if (r->empty()) continue;  // the trailing "" of "dir/"
    if (p == path.end() || *p != *r) return {};
  }
  fs::path rest;
  for (; p != path.end(); ++p) rest /= *p;
  return rest;
}

fs::path normal_absolute(const fs::path& path) {
  std::error_code ec;
  const fs::path absolute = fs::absolute(path, ec);
  return (ec ? path : absolute).lexically_normal();
}

}  // namespace

DisplayRoots::DisplayRoots(std::vector<fs::path> roots) : previous_(current_roots) {
  for (const auto& root : roots)
    if (!root.empty()) roots_.push_back(normal_absolute(root));
  current_roots = this;
}

DisplayRoots::~DisplayRoots() { current_roots = previous_; }

std::string display_path(const fs::path& path) {
  if (!current_roots || path.empty()) return path.string();
  const fs::path normal = normal_absolute(path);
  for (const DisplayRoots* roots = current_roots; roots; roots = roots->previous_) {
    for (const auto& root : roots->roots_) {
      if (normal == root) return root.filename().string();  // a root that is one file
      const fs::path rest = below(normal, root);
      if (!rest.empty()) return rest.generic_string();
    }
  }
  return path.string();
}

}  // namespace keel::io
