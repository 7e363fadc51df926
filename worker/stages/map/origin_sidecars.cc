#include "worker/stages/map/origin_sidecars.h"

#include <fstream>
#include <stdexcept>

#include "worker/pipeline/report.h"

namespace keel::pipeline {

nlohmann::json origin_json(const proto::GeoOrigin& origin) {
  nlohmann::json j = origin.to_json();
  j["frame"] = "ENU";
  return j;
}

size_t add_origin_to_sidecars(const std::filesystem::path& work_dir,
                              const std::vector<std::string>& artifacts,
                              const std::optional<proto::GeoOrigin>& origin) {
  if (!origin) return 0;
  size_t count = 0;
  for (const std::string& name : artifacts) {
    if (std::filesystem::path(name).extension() != ".json") continue;
    const std::filesystem::path path = work_dir / name;
    std::ifstream in(path);
    nlohmann::ordered_json doc = nlohmann::ordered_json::parse(in, nullptr, false);
    if (doc.is_discarded() || !doc.is_object())
      throw std::runtime_error(path.string() + ": not a JSON object; cannot add the origin");
    doc["origin"] = origin_json(*origin);
    write_json_atomically(path, doc);
    ++count;
  }
  return count;
}

}  // namespace keel::pipeline
