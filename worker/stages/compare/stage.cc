#include "worker/stages/compare/stage.h"
#include "worker/pipeline/report_html_parts.h"

#include <cmath>
#include <filesystem>

#include "proto/contract_error.h"
#include "worker/stages/compare/compare_hulls.h"
#include "worker/stages/compare/compare_maps.h"
#include "worker/stages/compare/compare_runs.h"
#include "worker/pipeline/report.h"
#include "worker/pipeline/stage_options.h"

namespace keel::pipeline {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using proto::ContractError;

void local_require(bool ok, const std::string& option, const std::string& expected) {
  if (!ok) throw ContractError("options.compare." + option + ": expected " + expected);
}

std::string id_of(const InputJob& job, const char* fallback) {
  return job.job.value("id", fallback);
}

// A reprocess job made with "compare": true (options.compare.job_a alone, the lease giving job
// A) compares A with its own products: B is this job, its report its earlier stages' sections.
InputJob this_job(const StageContext& context) {
  InputJob b;
  b.dir = context.work_dir;
  b.job = context.job;
  b.job["state"] = "succeeded";  // its stages before this one did
  b.report = {{"job", {{"options", context.job.value("options", json::object())}}},
              {"stages", context.reports}};
  return b;
}

// Step 1: refusals that name the reason.
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

class CompareStage : public Stage {
 public:
  std::string name() const override { return "compare"; }
  std::string report_html(const report_html::Ref& section,
                          const ReportHtmlInputs& inputs) const override {
    return report_html::compare_section(section);
  }
  StageResult run(StageContext& context) override {
    const CompareStageOptions options = CompareStageOptions::from_json(context.options);
    if (context.input_jobs.size() == 1 && context.options.contains("job_a") &&
        !context.options.contains("job_b"))
      context.input_jobs.push_back(this_job(context));
    check_pair(context.input_jobs);
    const InputJob& a = context.input_jobs[0];
    const InputJob& b = context.input_jobs[1];
    const std::vector<std::string> maps_a = map_names(a.dir), maps_b = map_names(b.dir);
    const bool hull_a = has_hull_products(a.dir), hull_b = has_hull_products(b.dir);
    const std::vector<std::string> maps = maps_to_compare(maps_a, maps_b, options);
    const bool hulls = hull_a && hull_b;
    const bool same_mission = !a.job.value("mission_id", "").empty() &&
                              a.job.value("mission_id", "") == b.job.value("mission_id", "");
    if (maps.empty() && !hulls && !same_mission)
      throw std::runtime_error("job " + id_of(a, "A") + " holds " + holds(maps_a, hull_a) +
                               " and job " + id_of(b, "B") + " " + holds(maps_b, hull_b) +
                               ": a map compares with a map, a hull with a hull");
    context.progress(0.02);

    StageResult out;
    json& r = out.report;
    r["job_a"] = id_of(a, "A");
    r["job_b"] = id_of(b, "B");
    r["kind"] = !maps.empty() ? (hulls ? "maps+hull" : "maps") : (hulls ? "hull" : "runs");
    if (!maps.empty()) r["maps"] = compare_maps(context, options, maps, &out.artifacts);
    if (hulls) r["hull"] = compare_hulls(context, options, &out.artifacts);
    r["runs"] = compare_runs(a, b);
    write_json_atomically(context.work_dir / kChangesFile, nlohmann::ordered_json(r));
    out.artifacts.push_back(kChangesFile);
    context.progress(1.0);
    return out;
  }
};

}  // namespace


CompareStageOptions CompareStageOptions::from_json(const json& options) {
  CompareStageOptions o;
  if (options.is_null()) return o;
  StageOptionReader r(options, "compare");
  // Set by the server on a compare job (POST /v1/comparisons); the jobs come as input_jobs.
  r.optional<std::string>("job_a", "");
  r.optional<std::string>("job_b", "");
  if (r.has("sensors")) {
    const json& list = r.at("sensors");
    local_require(list.is_array(), "sensors", "a list of map names");
    for (const auto& s : list) {
      local_require(s.is_string() && !s.get<std::string>().empty(), "sensors", "a list of map names");
      o.sensors.push_back(s.get<std::string>());
    }
  }
  o.register_maps = r.optional<bool>("register", o.register_maps);
  auto& g = o.registration;
  g.sample_spacing_m = r.optional<double>("registration_sample_spacing_m", g.sample_spacing_m);
  g.plane_radius_m = r.optional<double>("registration_plane_radius_m", g.plane_radius_m);
  g.max_correspondence_m =
      r.optional<double>("registration_max_correspondence_m", g.max_correspondence_m);
  g.stable_sigmas = r.optional<double>("registration_stable_sigmas", g.stable_sigmas);
  g.max_iterations = r.optional<int>("registration_max_iterations", g.max_iterations);
  o.local_registration_tile_m =
      r.optional<double>("local_registration_tile_m", o.local_registration_tile_m);
  auto& m = o.m3c2;
  m.normal_scale_m = r.optional<double>("normal_scale_m", m.normal_scale_m);
  m.projection_scale_m = r.optional<double>("projection_scale_m", m.projection_scale_m);
  m.max_depth_m = r.optional<double>("max_depth_m", m.max_depth_m);
  m.core_spacing_m = r.optional<double>("core_spacing_m", m.core_spacing_m);
  m.min_points = r.optional<int>("min_points", m.min_points);
  m.confidence_z = r.optional<double>("confidence_z", m.confidence_z);
  o.registration_error_m = r.optional<double>("registration_error_m", o.registration_error_m);
  o.histogram_bins = r.optional<int>("histogram_bins", o.histogram_bins);
  o.histogram_range_m = r.optional<double>("histogram_range_m", o.histogram_range_m);
  o.draco_position_bits = r.optional<int>("draco_position_bits", o.draco_position_bits);
  o.draco_field_bits = r.optional<int>("draco_field_bits", o.draco_field_bits);
  o.draco_compression_level = r.optional<int>("draco_compression_level", o.draco_compression_level);
  o.write_ply = r.optional<bool>("write_ply", o.write_ply);
  o.growth_sigmas = r.optional<double>("growth_sigmas", o.growth_sigmas);
  o.shape_max_offset_m = r.optional<double>("shape_max_offset_m", o.shape_max_offset_m);
  o.threads = r.optional<int>("threads", o.threads);
  r.finish();
  try {
    compare::validate(o.registration);
    compare::validate(o.m3c2);
  } catch (const std::invalid_argument& e) {
    throw ContractError(std::string("options.compare.") + e.what());
  }
  local_require(std::isfinite(o.local_registration_tile_m) && o.local_registration_tile_m >= 0,
          "local_registration_tile_m", "a number >= 0 (0: off)");
  local_require(std::isfinite(o.registration_error_m), "registration_error_m",
          "a number (< 0: from the registration)");
  local_require(o.histogram_bins >= 1 && o.histogram_bins <= 1000, "histogram_bins",
          "an integer in [1, 1000]");
  local_require(std::isfinite(o.histogram_range_m) && o.histogram_range_m > 0, "histogram_range_m",
          "> 0");
  local_require(o.draco_position_bits >= 1 && o.draco_position_bits <= 30, "draco_position_bits",
          "an integer in [1, 30]");
  local_require(o.draco_compression_level >= 0 && o.draco_compression_level <= 10,
          "draco_compression_level", "an integer in [0, 10]");
  local_require(o.draco_field_bits >= 0 && o.draco_field_bits <= 30, "draco_field_bits",
          "an integer in [0, 30]");
  local_require(std::isfinite(o.growth_sigmas) && o.growth_sigmas > 0, "growth_sigmas", "> 0");
  local_require(std::isfinite(o.shape_max_offset_m) && o.shape_max_offset_m >= 0 &&
              o.shape_max_offset_m <= 10,
          "shape_max_offset_m", "a length in [0, 10] m");
  local_require(o.threads >= 1 && o.threads <= 256, "threads", "an integer in [1, 256]");
  return o;
}

std::unique_ptr<Stage> make_compare_stage() { return std::make_unique<CompareStage>(); }

}  // namespace keel::pipeline
