#include "worker/io/bag/bag_source.h"

#include <set>

#include "worker/io/bag/bag_reader.h"
#include "worker/io/display_path.h"
#include "worker/io/io_error.h"
#include "worker/io/bag/rosbag2_reader.h"

namespace keel::io {

namespace fs = std::filesystem;

const BagTopicInfo& BagSource::topic(const std::string& name) const {
  for (const auto& t : topics())
    if (t.topic == name) return t;
  std::string known;
  for (const auto& t : topics())
    known += (known.empty() ? "" : ", ") + t.topic + " (" + t.datatype + ")";
  const std::string damaged = damage();
  throw IoError(display_path(path()) + ": no topic '" + name + "' in the bag (topics: " +
                (known.empty() ? "none" : known) + ")" + (damaged.empty() ? "" : "; " + damaged));
}

bool BagSource::has_topic(const std::string& name) const {
  for (const auto& t : topics())
    if (t.topic == name) return true;
  return false;
}

std::unique_ptr<BagSource> open_bag(const fs::path& path) {
  std::error_code ec;
  const std::string extension = path.extension().string();
  if (fs::is_directory(path, ec) || extension == ".mcap" || extension == ".db3")
    return std::make_unique<Rosbag2Reader>(path);
  return std::make_unique<BagReader>(path);
}

bool lookup_static_transform(const std::vector<StaticTransform>& transforms,
                             const std::string& target_frame, const std::string& source_frame,
                             Pose3& T_target_source) {
  // Path to the root from each frame (a TF tree: every child has one parent).
  auto chain_to_root = [&](const std::string& frame) {
    std::vector<std::pair<std::string, Pose3>> chain;  // (frame, T_root?_frame accumulated)
    Pose3 T_current_frame = Pose3::Identity();
    std::string current = frame;
    chain.emplace_back(current, T_current_frame);
    std::set<std::string> seen{current};
    while (true) {
      const StaticTransform* edge = nullptr;
      for (const auto& t : transforms)
        if (t.child_frame == current) edge = &t;
      if (!edge || seen.count(edge->parent_frame)) break;
      T_current_frame = edge->T_parent_child * T_current_frame;  // T_parent_frame
      current = edge->parent_frame;
      seen.insert(current);
      chain.emplace_back(current, T_current_frame);
    }
    return chain;  // chain[k] = (ancestor_k, T_ancestor_k_frame)
  };
  const auto source_chain = chain_to_root(source_frame);
  const auto target_chain = chain_to_root(target_frame);
  for (const auto& [ancestor, T_ancestor_source] : source_chain)
    for (const auto& [other, T_other_target] : target_chain)
      if (ancestor == other) {
        T_target_source = T_other_target.inverse() * T_ancestor_source;
        return true;
      }
  return false;
}

}  // namespace keel::io
