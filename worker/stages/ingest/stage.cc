// Stage `ingest` (docs/mission-format.md) as its numbered steps:
//   1. options; mission.yaml loaded with the job's extrinsic overrides (load_job_mission);
//   2. every sensor's records read once (one scan in memory at a time, image headers only):
//      counts, time spans, measured vs nominal rate, gaps, point statistics and the span of
//      the per-point time field;
//   3. every trajectory: poses, span and path length; the loop closures counted;
//   4. with a CAD mesh: its size, area, closedness, degenerate triangles and a units check;
//   5. the report: the mission's header, the sections above and every warning.
#include "worker/stages/ingest/stage.h"

#include "worker/io/mission_reader.h"
#include "worker/pipeline/job_extrinsics.h"
#include "worker/pipeline/report_html_parts.h"
#include "worker/stages/ingest/mission_report.h"

namespace keel::pipeline {
namespace {

using nlohmann::json;

json mission_header(const proto::MissionManifest& manifest) {
  auto or_null = [](const std::string& s) { return s.empty() ? json(nullptr) : json(s); };
  return {{"name", manifest.name},
          {"platform", proto::to_string(manifest.platform)},
          {"body_frame", manifest.body_frame},
          {"world_frame", manifest.world_frame},
          {"bag", or_null(manifest.bag)},
          {"cad_mesh", or_null(manifest.cad_mesh)},
          {"ground_truth", or_null(manifest.ground_truth)}};
}

class IngestStage : public Stage {
 public:
  std::string name() const override { return "ingest"; }
  const OptionsSchema& options() const override { return ingest_option_table(); }
  std::string report_html(const report_html::Ref& section, const ReportHtmlInputs&) const override {
    return report_html::ingest_section(section);
  }

  StageResult run(StageContext& context) override {
    // 1. Options and the mission.
    const IngestOptions options = ingest_option_table().from_json(context.options);
    io::MissionReader reader(load_job_mission(context));
    const auto& manifest = reader.manifest();
    json warnings = json::array();
    const std::filesystem::path cad_path =
        !context.cad_path.empty() ? context.cad_path : reader.mission().cad_mesh_path;
    const size_t units =
        manifest.sensors.size() + manifest.trajectories.size() + (cad_path.empty() ? 1 : 2);
    size_t done = 0;
    auto progress = [&](double within) {
      context.progress((done + within) / static_cast<double>(units));
    };

    // 2. Sensors.
    json sensors = json::object();
    for (const auto& sensor : manifest.sensors) {
      context.check_canceled();
      sensors[sensor.name] = sensor_report(reader, sensor, options, context, warnings, progress);
      context.log(sensor.name + " (" + proto::to_string(sensor.type) +
                  "): " + std::to_string(sensors[sensor.name]["count"].get<size_t>()) + " records");
      ++done;
      progress(0.0);
    }

    // 3. Trajectories and loop closures.
    json trajectories = json::object();
    for (const auto& [name, spec] : manifest.trajectories) {
      context.check_canceled();
      trajectories[name] = trajectory_report(reader.read_trajectory(name), options, name, warnings);
      trajectories[name]["source"] = spec.topic.empty() ? spec.file : "topic " + spec.topic;
      ++done;
      progress(0.0);
    }
    context.check_canceled();
    const auto loops = reader.read_loop_closures();

    // 4. The CAD mesh.
    json cad = nullptr;
    if (!cad_path.empty()) {
      ++done;
      progress(0.0);
      context.check_canceled();
      cad = cad_report(cad_path, warnings);
      context.log("cad: " + std::to_string(cad["num_faces"].get<size_t>()) + " triangles, " +
                  (cad["closed"].get<bool>() ? "closed" : "open"));
    }
    context.progress(1.0);

    // 5. The report.
    StageResult result;
    result.report = {
        {"mission", mission_header(manifest)}, {"sensors", sensors}, {"trajectories", trajectories},
        {"loop_closures", loops.size()},       {"cad", cad},         {"warnings", warnings}};
    return result;
  }
};

}  // namespace

std::unique_ptr<Stage> make_ingest_stage() { return std::make_unique<IngestStage>(); }

}  // namespace keel::pipeline
