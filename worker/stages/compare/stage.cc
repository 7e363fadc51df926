// Stage `compare` (issue 16) as its numbered steps:
//   1. options (--set compare.x=v); what the jobs hold decides what is compared: maps (both
//      have map_<sensor>.drc), hulls (both have mesh_remeshed.drc, shapes.json and
//      ba_solution.json); a map job against a hull job, or jobs with nothing in common, are
//      refused with the reason (job_pair.h);
//   2. maps: B registered onto A on stable structure (compare/stable_registration.h), then per
//      map the C2C distance of every point of B and its M3C2 change with the 95 % level of
//      detection (compare/m3c2.h): change_<sensor>.drc / .ply (compare_maps.h);
//   3. hulls: the x_gM difference, each vertex's deviation in B minus A (change_hull.drc /
//      .ply, model frame), shapes matched by overlap in the model frame: new, gone, and the
//      height and footprint growth of each shape kept, with uncertainties
//      (compare/shape_matching.h, compare_hulls.h);
//   4. runs: every figure of A's and B's report.json side by side with its difference, the
//      options that differ and, with both refined trajectories, B's ATE against A's
//      (compare_runs.h);
//   5. changes.json: the stage's report section.
#include "worker/stages/compare/stage.h"

#include "worker/pipeline/report.h"
#include "worker/pipeline/report_html_parts.h"
#include "worker/stages/compare/compare_hulls.h"
#include "worker/stages/compare/compare_maps.h"
#include "worker/stages/compare/compare_runs.h"
#include "worker/stages/compare/job_pair.h"

namespace keel::pipeline {
namespace {

class CompareStage : public Stage {
 public:
  std::string name() const override { return "compare"; }
  const OptionsSchema& options() const override { return compare_option_table(); }
  std::string report_html(const report_html::Ref& section, const ReportHtmlInputs&) const override {
    return report_html::compare_section(section);
  }

  StageResult run(StageContext& context) override {
    // 1. Options, the two jobs and what they hold.
    const CompareStageOptions options = compare_option_table().from_json(context.options);
    if (context.input_jobs.size() == 1 && context.options.contains("job_a") &&
        !context.options.contains("job_b"))
      context.input_jobs.push_back(this_job(context));
    const Comparison comparison = what_to_compare(context.input_jobs, options);
    const InputJob& a = context.input_jobs[0];
    const InputJob& b = context.input_jobs[1];
    context.progress(0.02);

    StageResult out;
    nlohmann::json& r = out.report;
    r["job_a"] = id_of(a, "A");
    r["job_b"] = id_of(b, "B");
    r["kind"] = comparison.kind();
    // 2. Maps.
    if (!comparison.maps.empty())
      r["maps"] = compare_maps(context, options, comparison.maps, &out.artifacts);
    // 3. Hulls.
    if (comparison.hulls) r["hull"] = compare_hulls(context, options, &out.artifacts);
    // 4. Runs.
    r["runs"] = compare_runs(a, b);
    // 5. changes.json.
    write_json_atomically(context.work_dir / kChangesFile, nlohmann::ordered_json(r));
    out.artifacts.push_back(kChangesFile);
    context.progress(1.0);
    return out;
  }
};

}  // namespace

std::unique_ptr<Stage> make_compare_stage() { return std::make_unique<CompareStage>(); }

}  // namespace keel::pipeline
