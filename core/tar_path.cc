#include "core/tar_path.h"

#include <algorithm>

namespace keel {

std::vector<std::string> tar_path_components(const std::string& name) {
  std::vector<std::string> parts;
  size_t start = 0;
  while (start <= name.size()) {
    size_t slash = name.find('/', start);
    if (slash == std::string::npos) slash = name.size();
    std::string part = name.substr(start, slash - start);
    if (!part.empty() && part != ".") parts.push_back(std::move(part));
    start = slash + 1;
  }
  return parts;
}

std::string join_tar_path(const std::vector<std::string>& parts, size_t count) {
  std::string out;
  for (size_t i = 0; i < std::min(count, parts.size()); ++i) out += (i ? "/" : "") + parts[i];
  return out;
}

bool has_parent_component(const std::vector<std::string>& parts) {
  return std::find(parts.begin(), parts.end(), "..") != parts.end();
}

}  // namespace keel
