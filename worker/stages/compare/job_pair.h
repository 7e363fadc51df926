// Step 1 of the compare stage: the two jobs, A (earlier) and B (later), and what may be
// compared between them. Refusals name the reason, which becomes the job's error.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "worker/pipeline/stage.h"
#include "worker/stages/compare/options.h"

namespace keel::pipeline {

// The job's record's id, else `fallback`.
std::string id_of(const InputJob& job, const char* fallback);

// A reprocess job made with "compare": true (options.compare.job_a alone, the lease giving job
// A) compares A with its own products: B is this job, its report its earlier stages' sections.
InputJob this_job(const StageContext& context);

// The maps a job folder holds: "<name>" for every map_<name>.drc (previews left out), sorted.
std::vector<std::string> map_names(const std::filesystem::path& dir);

// The maps to compare: options.sensors, else `combined` when both have it, else every map
// both have. Throws std::runtime_error naming what is missing.
std::vector<std::string> maps_to_compare(const std::vector<std::string>& a,
                                         const std::vector<std::string>& b,
                                         const CompareStageOptions& options);

// What is compared, from what both jobs hold: maps (both have map_<sensor>.drc), a hull (both
// have mesh_remeshed.drc, shapes.json and ba_solution.json), and always the runs.
struct Comparison {
  std::vector<std::string> maps;
  bool hulls = false;
  std::string kind() const;  // "maps", "hull", "maps+hull" or "runs"
};

// Throws std::runtime_error unless the jobs are two finished jobs of one project that hold
// something to compare: a map job against a hull job, or jobs with nothing in common that are
// not of the same mission, are refused.
Comparison what_to_compare(const std::vector<InputJob>& jobs, const CompareStageOptions& options);

}  // namespace keel::pipeline
