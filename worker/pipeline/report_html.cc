// report.html, the document: head and style, the job's summary, one section per stage in the
// job's order, then every figure of report.json (all_figures). The stages' sections are in
// report_html_<stage>.cc.
#include "worker/pipeline/report_html.h"

#include <cmath>
#include <fstream>
#include <sstream>

#include "core/replaced_file.h"
#include "proto/options.h"
#include "worker/pipeline/html_text.h"
#include "worker/pipeline/report.h"
#include "worker/pipeline/report_html_parts.h"
#include "worker/pipeline/stage.h"
#include "worker/pipeline/trajectories_file.h"

namespace keel::pipeline {

namespace report_html {

namespace {

constexpr const char* kStyle =
    "body{font-family:sans-serif;margin:24px auto;max-width:1100px;color:#222;line-height:1.4}"
    "h1{font-size:22px}h2{font-size:19px;border-bottom:2px solid #1f77b4;margin-top:36px}"
    "h3{font-size:15px;margin-top:22px}"
    "table{border-collapse:collapse;margin:8px 0 16px;font-size:13px}"
    "caption{text-align:left;font-weight:bold;padding:4px 0}"
    "th,td{border:1px solid #ccc;padding:3px 8px;text-align:left;vertical-align:top}"
    "th{background:#f2f4f7}td data{font-variant-numeric:tabular-nums}"
    "figure{margin:8px 0 18px}figcaption{font-size:12px;color:#555;max-width:640px}"
    ".failed{background:#fdecea;border:1px solid #d62728;padding:8px 12px}"
    ".warn li{color:#8a4b00}details summary{cursor:pointer;font-weight:bold}"
    "code{font-size:12px}";

// One row per leaf below `ref`.
void collect_leaves(const Ref& ref, std::vector<std::vector<std::string>>& rows) {
  const Json& value = ref.json();
  if (value.is_object() && !value.empty()) {
    for (const auto& item : value.items()) collect_leaves(ref[item.key()], rows);
    return;
  }
  if (value.is_array() && !value.empty()) {
    for (size_t i = 0; i < value.size(); ++i) collect_leaves(ref[i], rows);
    return;
  }
  rows.push_back({"<code>" + html::escape(ref.pointer()) + "</code>", ref.cell()});
}

// The extrinsics the job used and where each came from (docs/calibration.md).
std::string calibration_table(const Ref& calibration) {
  if (calibration.missing() || !calibration.json().is_object()) return "";
  Table t{"calibration",
          "Extrinsics used (T_body_sensor)",
          {"sensor", "source", "x, y, z (m)", "roll, pitch, yaw (deg)"},
          {}};
  auto triple = [](const Ref& values, int decimals) {
    std::string out;
    for (const auto& v : values.json()) {
      std::ostringstream text;
      text.precision(decimals);
      text << std::fixed << (v.is_number() ? v.get<double>() : 0.0);
      out += (out.empty() ? "" : ", ") + text.str();
    }
    return html::escape(out);
  };
  for (const auto& item : calibration.json().items()) {
    const Ref sensor = calibration[item.key()];
    t.rows.push_back({html::escape(item.key()), html::escape(sensor["source"].text()),
                      triple(sensor["xyz_m"], 3), triple(sensor["rpy_deg"], 2)});
  }
  return t.rows.empty() ? "" : render(t);
}

std::string summary_section(const Ref& report) {
  std::string out = "<section id=\"summary\">";
  const Ref job = report["job"];
  const Ref mission = report["mission"];
  Table t{"job", "Job", {"", ""}, {}};
  t.rows.push_back({"job", job["id"].cell()});
  if (!mission["name"].missing()) t.rows.push_back({"mission", mission["name"].cell()});
  if (!mission["id"].missing()) t.rows.push_back({"mission id", mission["id"].cell()});
  if (!mission["path"].missing()) t.rows.push_back({"mission folder", mission["path"].cell()});
  std::string stages;
  for (const auto& s : job["stages"].json()) stages += (stages.empty() ? "" : ", ") + s.dump();
  t.rows.push_back({"stages", html::escape(stages)});
  if (!job["attempts"].missing()) t.rows.push_back({"attempts", job["attempts"].cell()});
  out += render(t);
  const Ref failed = report["failed"];
  if (!failed.missing())
    out += "<p class=\"failed\" id=\"failure\"><strong>The job failed in stage " +
           html::escape(failed["stage"].text()) + ":</strong> " +
           html::escape(failed["error"].text()) +
           ". The figures below are those of the stages that finished.</p>";
  Table times{"stage-seconds", "Time per stage", {"stage", "wall time"}, {}};
  for (const auto& item : report["stage_seconds"].json().items())
    times.rows.push_back({html::escape(item.key()), report["stage_seconds"][item.key()].cell("s")});
  if (!times.rows.empty()) out += render(times);
  out += calibration_table(report["calibration"]);
  return out + "</section>";
}

}  // namespace

std::string all_figures(const Ref& report) {
  Table t{"all-figures", "", {"JSON pointer in report.json", "value"}, {}};
  collect_leaves(report, t.rows);
  return "<section id=\"all\"><h2>Every figure of report.json</h2><details><summary>" +
         std::to_string(t.rows.size()) + " values, by JSON pointer</summary>" + render(t) +
         "</details></section>";
}

}  // namespace report_html

std::string render_report_html(const nlohmann::ordered_json& report,
                               const nlohmann::json& trajectories) {
  using namespace report_html;
  const Ref root(report, "");
  const Ref mission = root["mission"];
  const std::string name =
      mission["name"].json().is_string() ? mission["name"].text() : root["job"]["id"].text();
  std::string page =
      "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"/>"
      "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\"/>"
      "<title>Keel report: " +
      html::escape(name) + "</title><style>" + kStyle + "</style></head><body>";
  page += "<h1>Keel report: " + html::escape(name) + "</h1>";
  page += summary_section(root);
  ReportHtmlInputs inputs;
  inputs.trajectories = trajectories;
  const Ref stages = root["stages"];
  for (const auto& item : stages.json().items()) {
    const std::string& stage = item.key();
    const Ref section = stages[stage];
    page +=
        "<section id=\"stage-" + html::escape(stage) + "\"><h2>" + html::escape(stage) + "</h2>";
    if (proto::is_known_stage(stage)) page += make_stage(stage)->report_html(section, inputs);
    page += "</section>";
  }
  page += all_figures(root);
  return page + "</body></html>\n";
}

std::vector<std::string> write_report_files(const std::filesystem::path& work_dir,
                                            const nlohmann::ordered_json& report) {
  write_json_atomically(work_dir / kReportFileName, report);
  // The ATE over time comes from trajectories.json; a page without it beats no page.
  nlohmann::json trajectories = nullptr;
  std::ifstream in(work_dir / kTrajectoriesFile);
  if (in) trajectories = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  if (trajectories.is_discarded()) trajectories = nullptr;
  write_file_replacing(work_dir / kReportHtmlFileName, render_report_html(report, trajectories));
  return {kReportFileName, kReportHtmlFileName};
}

}  // namespace keel::pipeline
