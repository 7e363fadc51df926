// A processing stage: reads the mission (and earlier stages' outputs) from disk, writes its
// artifacts into the job's work folder and returns its section of report.json; it also renders
// that section for report.html and owns the table of its options. Each stage lives in its own
// folder, worker/stages/<name>/ (stage.cc its numbered steps, options.cc its option table,
// report_html.cc its report section, artifacts.h the files other stages read of it).
// Stages know nothing of HTTP or databases: the same stage runs under `keel-worker` (leased
// from a server) and `keel-worker run` (local, no server).
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "proto/stages.h"

namespace keel::pipeline {

class OptionsSchema;  // option_table.h
namespace report_html {
class Ref;  // report_html_parts.h
}

// What a stage's report.html section may read besides its section of report.json.
struct ReportHtmlInputs {
  nlohmann::json trajectories = nullptr;  // trajectories.json of the work folder, or null
};

// Thrown by StageContext::check_canceled(); the runner stops and reports nothing more.
struct Canceled : std::runtime_error {
  Canceled() : std::runtime_error("job canceled") {}
};

// A finished job that a `compare` stage reads: its artifacts, downloaded into `dir` (report.json
// among them), and its record ({"id", "mission_id", "project", "stages", "options", ...}).
// `report`, when not null, stands for dir/report.json: the job running the stage compares with
// itself (a reprocess with "compare": true), its report so far being its earlier stages.
struct InputJob {
  std::filesystem::path dir;
  nlohmann::json job = nlohmann::json::object();
  nlohmann::json report = nullptr;
};

struct StageContext {
  std::filesystem::path mission_dir;  // unpacked mission bundle (mission.yaml at its root)
  std::filesystem::path cad_path;     // CAD mesh file, empty when the mission has none
  std::filesystem::path work_dir;     // artifacts of every stage of this job live here
  nlohmann::json options = nlohmann::json::object();  // this stage's options (--set stage.x=v)
  // The job's extrinsic overrides, options.calibration (docs/calibration.md), or null; stages
  // read the mission through load_job_mission (job_extrinsics.h), which applies them.
  nlohmann::json calibration = nullptr;
  nlohmann::json reports = nlohmann::json::object();  // sections of earlier stages, by stage name
  std::vector<InputJob> input_jobs;  // `compare`: the earlier job A, then the later job B
  // The job's own record from its lease ({"id", "mission_id", "project", "options", ...});
  // empty when the pipeline runs without a server (keel-worker run).
  nlohmann::json job = nlohmann::json::object();

  // Progress of this stage in [0, 1]; a line for the job log. Both cheap; call freely.
  std::function<void(double)> progress = [](double) {};
  std::function<void(const std::string&)> log = [](const std::string&) {};
  // True once the job is canceled; stages call check_canceled() in their loops.
  std::function<bool()> canceled = [] { return false; };
  void check_canceled() const {
    if (canceled()) throw Canceled();
  }
};

struct StageResult {
  nlohmann::json report = nlohmann::json::object();  // this stage's section of report.json
  std::vector<std::string> artifacts;                // file names written into work_dir
};

class Stage {
 public:
  virtual ~Stage() = default;
  virtual std::string name() const = 0;
  // Throws std::exception with a message naming what is wrong; that message becomes the
  // job's error.
  virtual StageResult run(StageContext& context) = 0;
  // Its section of report.html (HTML elements, within the page's <section> of the stage) from
  // its section of report.json. Pure. None by default.
  virtual std::string report_html(const report_html::Ref& section,
                                  const ReportHtmlInputs& inputs) const {
    return "";
  }
  // Its options: the stage reads them, the docs list them and `keel-worker options` prints
  // them from this one table. None by default (only {} is accepted).
  virtual const OptionsSchema& options() const;
};

// The stages built into this worker, by name ("ingest", ...), from proto/stages.h's one list.
// Throws for an unknown name.
std::unique_ptr<Stage> make_stage(const std::string& name);
std::vector<std::string> available_stages();

// Each stage's factory, defined in its folder's stage.cc.
#define KEEL_DECLARE_STAGE_FACTORY(name) std::unique_ptr<Stage> make_##name##_stage();
KEEL_STAGES(KEEL_DECLARE_STAGE_FACTORY)
#undef KEEL_DECLARE_STAGE_FACTORY

}  // namespace keel::pipeline
