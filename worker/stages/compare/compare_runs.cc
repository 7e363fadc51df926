#include "worker/stages/compare/compare_runs.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include "worker/io/tum.h"
#include "worker/pipeline/report.h"
#include "worker/slam/trajectory_metrics.h"

namespace keel::pipeline {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

json load_report(const InputJob& input, const std::string& which) {
  if (!input.report.is_null()) return input.report;
  const fs::path path = input.dir / kReportFileName;
  std::ifstream in(path);
  if (!in) throw std::runtime_error("job " + input.job.value("id", which) + " has no report.json");
  try {
    return json::parse(in);
  } catch (const json::parse_error& e) {
    throw std::runtime_error("job " + input.job.value("id", which) +
                             ": report.json is not valid JSON: " + e.what());
  }
}

// The job record's options, else the report's copy of them.
json job_options(const InputJob& input, const json& report) {
  if (input.job.contains("options") && input.job["options"].is_object())
    return input.job["options"];
  if (report.contains("job") && report["job"].contains("options")) return report["job"]["options"];
  return json::object();
}

json stats_json(const slam::ErrorStatistics& s) {
  return {{"count", s.count}, {"rmse", s.rmse}, {"mean", s.mean}, {"median", s.median},
          {"std", s.std},     {"min", s.min},   {"max", s.max}};
}

}  // namespace

void flatten_numbers(const json& document, const std::string& prefix,
                     std::vector<std::pair<std::string, double>>* out) {
  if (document.is_number()) {
    out->emplace_back(prefix, document.get<double>());
    return;
  }
  if (!document.is_object()) return;
  for (const auto& [key, value] : document.items())
    flatten_numbers(value, prefix.empty() ? key : prefix + "." + key, out);
}

json options_difference(const json& a, const json& b) {
  std::map<std::string, std::pair<json, json>> all;
  for (const json* side : {&a, &b}) {
    if (!side->is_object()) continue;
    for (const auto& [stage, options] : side->items()) {
      if (!options.is_object()) continue;
      for (const auto& [key, value] : options.items()) {
        auto& entry = all[stage + "." + key];
        (side == &a ? entry.first : entry.second) = value;
      }
    }
  }
  json out = json::array();
  for (const auto& [name, values] : all)
    if (values.first != values.second)
      out.push_back({{"option", name}, {"a", values.first}, {"b", values.second}});
  return out;
}

json compare_runs(const InputJob& a, const InputJob& b, size_t max_figures) {
  const json report_a = load_report(a, "A"), report_b = load_report(b, "B");
  json out;
  const std::string mission_a = a.job.value("mission_id", ""),
                    mission_b = b.job.value("mission_id", "");
  out["same_mission"] = !mission_a.empty() && mission_a == mission_b;
  out["options_differ"] = options_difference(job_options(a, report_a), job_options(b, report_b));

  // Figures of the stages' sections (report.json "stages"), and their times.
  std::vector<std::pair<std::string, double>> fa, fb;
  flatten_numbers(report_a.value("stages", json::object()), "", &fa);
  flatten_numbers(report_a.value("stage_seconds", json::object()), "stage_seconds", &fa);
  flatten_numbers(report_b.value("stages", json::object()), "", &fb);
  flatten_numbers(report_b.value("stage_seconds", json::object()), "stage_seconds", &fb);
  std::map<std::string, double> mb(fb.begin(), fb.end());
  std::set<std::string> in_a;
  json figures = json::array();
  size_t both = 0, differ = 0;
  for (const auto& [path, va] : fa) {
    in_a.insert(path);
    const auto it = mb.find(path);
    if (it == mb.end()) continue;
    ++both;
    const double vb = it->second;
    if (va != vb) ++differ;
    if (figures.size() >= max_figures) continue;
    json row = {{"figure", path}, {"a", va}, {"b", vb}, {"difference", vb - va}};
    if (va != 0.0) row["relative"] = (vb - va) / std::abs(va);
    figures.push_back(row);
  }
  size_t only_b = 0;
  for (const auto& [path, v] : fb) only_b += !in_a.count(path);
  out["figures"] = figures;
  out["figures_in_both"] = both;
  out["figures_that_differ"] = differ;
  out["figures_only_in_a"] = fa.size() - both;
  out["figures_only_in_b"] = only_b;
  out["figures_listed"] = figures.size();

  // B's trajectories against A's (A as the reference), associated by time.
  json trajectories = json::object();
  for (const char* name : {"trajectory_refined.tum", "trajectory_ba.tum"}) {
    std::error_code ec;
    if (!fs::is_regular_file(a.dir / name, ec) || !fs::is_regular_file(b.dir / name, ec)) continue;
    const Trajectory ta = io::read_tum(a.dir / name), tb = io::read_tum(b.dir / name);
    json entry;
    try {
      for (const auto& [label, alignment] :
           {std::pair<const char*, slam::Alignment>{"none", slam::Alignment::kNone},
            {"se3", slam::Alignment::kSE3}}) {
        const slam::AteResult ate = slam::absolute_trajectory_error(ta, tb, alignment);
        entry[std::string("ate_") + label] = {{"translation_m", stats_json(ate.translation_m)},
                                              {"rotation_deg", stats_json(ate.rotation_deg)}};
      }
    } catch (const std::exception& e) {
      entry = {{"error", std::string("not comparable: ") + e.what()}};
    }
    trajectories[name] = entry;
  }
  out["relative_ate"] = trajectories;
  return out;
}

}  // namespace keel::pipeline
