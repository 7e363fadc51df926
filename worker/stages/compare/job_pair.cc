#include "worker/stages/compare/job_pair.h"

#include <algorithm>
#include <filesystem>
#include <stdexcept>

#include "worker/pipeline/report.h"
#include "worker/stages/compare/compare_hulls.h"
#include "worker/stages/map/artifacts.h"

namespace keel::pipeline {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// Two finished jobs of one project.
void check_pair(const std::vector<InputJob>& jobs) {
  if (jobs.size() != 2)
    throw std::runtime_error("compare needs two finished jobs, A (earlier) and B (later); got " +
                             std::to_string(jobs.size()));
  for (const InputJob& j : jobs) {
    if (!j.report.is_null()) continue;  // this job itself
    const std::string state = j.job.value("state", "succeeded");
    if (state != "succeeded")
      throw std::runtime_error("job " + id_of(j, "?") + " is " + state +
                               ": only finished (succeeded) jobs can be compared");
    std::error_code ec;
    if (!fs::is_regular_file(j.dir / kReportFileName, ec))
      throw std::runtime_error("job " + id_of(j, "?") + " has no report.json");
  }
  const std::string pa = jobs[0].job.value("project", ""), pb = jobs[1].job.value("project", "");
  if (pa != pb)
    throw std::runtime_error("job " + id_of(jobs[0], "A") + " belongs to project '" + pa +
                             "' and job " + id_of(jobs[1], "B") + " to project '" + pb +
                             "': only jobs of one project can be compared");
}

std::string holds(const std::vector<std::string>& maps, bool hull) {
  if (!maps.empty() && hull) return "maps and a remeshed hull";
  if (!maps.empty()) return "maps (stage map)";
  if (hull) return "a remeshed hull (stages ba, inspect)";
  return "neither maps nor a remeshed hull";
}

}  // namespace

std::vector<std::string> map_names(const fs::path& dir) {
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    const std::string prefix = "map_", suffix = ".drc";
    if (name.size() <= prefix.size() + suffix.size() || name.rfind(prefix, 0) != 0 ||
        name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0)
      continue;
    const std::string map = name.substr(prefix.size(), name.size() - prefix.size() - suffix.size());
    if (map.size() > 8 && map.compare(map.size() - 8, 8, "_preview") == 0) continue;
    out.push_back(map);
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<std::string> maps_to_compare(const std::vector<std::string>& a,
                                         const std::vector<std::string>& b,
                                         const CompareStageOptions& options) {
  auto has = [](const std::vector<std::string>& list, const std::string& name) {
    return std::find(list.begin(), list.end(), name) != list.end();
  };
  if (!options.sensors.empty()) {
    for (const auto& s : options.sensors) {
      if (!has(a, s))
        throw std::runtime_error("options.compare.sensors: job A has no map '" + s + "'");
      if (!has(b, s))
        throw std::runtime_error("options.compare.sensors: job B has no map '" + s + "'");
    }
    return options.sensors;
  }
  if (has(a, kCombinedMapName) && has(b, kCombinedMapName)) return {kCombinedMapName};
  std::vector<std::string> both;
  for (const auto& s : a)
    if (has(b, s)) both.push_back(s);
  return both;
}

std::string id_of(const InputJob& job, const char* fallback) {
  return job.job.value("id", fallback);
}

InputJob this_job(const StageContext& context) {
  InputJob b;
  b.dir = context.work_dir;
  b.job = context.job;
  b.job["state"] = "succeeded";  // its stages before this one did
  b.report = {{"job", {{"options", context.job.value("options", json::object())}}},
              {"stages", context.reports}};
  return b;
}

std::string Comparison::kind() const {
  return !maps.empty() ? (hulls ? "maps+hull" : "maps") : (hulls ? "hull" : "runs");
}

Comparison what_to_compare(const std::vector<InputJob>& jobs, const CompareStageOptions& options) {
  check_pair(jobs);
  const InputJob& a = jobs[0];
  const InputJob& b = jobs[1];
  const std::vector<std::string> maps_a = map_names(a.dir), maps_b = map_names(b.dir);
  const bool hull_a = has_hull_products(a.dir), hull_b = has_hull_products(b.dir);
  Comparison out;
  out.maps = maps_to_compare(maps_a, maps_b, options);
  out.hulls = hull_a && hull_b;
  const bool same_mission = !a.job.value("mission_id", "").empty() &&
                            a.job.value("mission_id", "") == b.job.value("mission_id", "");
  if (out.maps.empty() && !out.hulls && !same_mission)
    throw std::runtime_error("job " + id_of(a, "A") + " holds " + holds(maps_a, hull_a) +
                             " and job " + id_of(b, "B") + " " + holds(maps_b, hull_b) +
                             ": a map compares with a map, a hull with a hull");
  return out;
}

}  // namespace keel::pipeline
