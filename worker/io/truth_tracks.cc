#include "worker/io/truth_tracks.h"

#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "worker/io/io_error.h"
#include "worker/io/yaml_json.h"

namespace keel::io {

std::optional<std::filesystem::path> truth_tracks_file(const std::filesystem::path& truth_yaml,
                                                       const std::string& camera) {
  const nlohmann::json truth = load_yaml_file(truth_yaml);
  const nlohmann::json* files =
      truth.contains("feature_tracks") ? &truth["feature_tracks"] : nullptr;
  if (!files || !files->is_object() || !files->contains(camera)) return std::nullopt;
  return truth_yaml.parent_path() / (*files)[camera].get<std::string>();
}

std::vector<TruthTrackPixel> read_truth_tracks(const std::filesystem::path& csv) {
  std::ifstream in(csv);
  if (!in) throw IoError(csv.string() + ": cannot open");
  std::string line;
  std::getline(in, line);
  if (line.rfind("id,t,u,v", 0) != 0) throw IoError(csv.string() + ":1: expected header id,t,u,v");
  std::vector<TruthTrackPixel> out;
  for (int number = 2; std::getline(in, line); ++number) {
    if (line.empty()) continue;
    std::istringstream row(line);
    std::string id, t, u, v;
    if (!std::getline(row, id, ',') || !std::getline(row, t, ',') || !std::getline(row, u, ',') ||
        !std::getline(row, v, ','))
      throw IoError(csv.string() + ":" + std::to_string(number) + ": expected 4 columns id,t,u,v");
    try {
      TruthTrackPixel p;
      p.t_ns = std::llround(std::stold(t) * 1e9L);
      p.pixel = Eigen::Vector2d(std::stod(u), std::stod(v));
      p.landmark_id = std::stoll(id);
      out.push_back(p);
    } catch (const std::logic_error&) {
      throw IoError(csv.string() + ":" + std::to_string(number) +
                    ": expected numbers in id,t,u,v, got '" + line + "'");
    }
  }
  return out;
}

}  // namespace keel::io
