// report.html, stage `calibrate`: per candidate, initial against refined T_reference_candidate
// with sigmas, the unobservable directions in words, the point-to-plane residuals and the
// combined cloud's Table V metrics before and after, and the reprocess line to copy.
#include "worker/pipeline/html_text.h"
#include "worker/pipeline/report_html_parts.h"
#include "worker/stages/calibrate/stage.h"

namespace keel::pipeline::report_html {
namespace {

const char* const kAxes[] = {"x (m)", "y (m)", "z (m)", "roll (deg)", "pitch (deg)", "yaw (deg)"};

std::string pose_table(const Ref& c) {
  const std::string name = c["sensor"].text();
  Table t{"calibrate-" + name,
          "T_reference_" + name + ": initial (" + c["initial"]["source"].text() + ") and refined",
          {"", "initial", "refined", "change", "sigma"},
          {}};
  const Ref initial = c["initial"]["T_reference_candidate"];
  const Ref refined = c["refined"]["T_reference_candidate"];
  for (size_t i = 0; i < 6; ++i) {
    const char* part = i < 3 ? "xyz_m" : "rpy_deg";
    const size_t k = i % 3;
    const double change = refined[part][k].number() - initial[part][k].number();
    t.rows.push_back({kAxes[i], initial[part][k].cell(), refined[part][k].cell(),
                      html::escape(html::format_shown(change)), c["sigma"][part][k].cell()});
  }
  return render(t);
}

std::string quality_table(const Ref& c) {
  const std::string name = c["sensor"].text();
  Table t{"calibrate-" + name + "-quality",
          name + ": point-to-plane residuals (m) and the combined cloud's metrics (Table V means)",
          {"", "initial", "refined"},
          {}};
  const Ref before = c["residuals"]["before"], after = c["residuals"]["after"];
  t.rows.push_back({"matched points", before["matched"].cell(), after["matched"].cell()});
  t.rows.push_back({"residual median", before["median_m"].cell("m"), after["median_m"].cell("m")});
  t.rows.push_back({"residual p90", before["p90_m"].cell("m"), after["p90_m"].cell("m")});
  const Ref mb = c["metrics"]["before"], ma = c["metrics"]["after"];
  t.rows.push_back({"surface density", mb["surface_density_per_m2"]["mean"].cell("points/m^2"),
                    ma["surface_density_per_m2"]["mean"].cell("points/m^2")});
  t.rows.push_back(
      {"roughness", mb["roughness_m"]["mean"].cell("m"), ma["roughness_m"]["mean"].cell("m")});
  t.rows.push_back({"planarity", mb["planarity"]["mean"].cell(), ma["planarity"]["mean"].cell()});
  return render(t);
}

std::string candidate_section(const Ref& c) {
  const std::string name = c["sensor"].text();
  std::string out = heading(name + ": " + c["status"].text(), "calibrate-" + name + "-heading");
  if (c["status"].text() == "refused") return out + paragraph(c["reason"].text());
  out += pose_table(c) + quality_table(c);
  out += string_list(c["warnings"], "Warnings");
  const Ref unobservable = c["unobservable"];
  if (unobservable.json().empty()) {
    out += paragraph("Every direction is observable.");
  } else {
    out += "<p>Unobservable here (left at the initial value):</p><ul>";
    for (size_t i = 0; i < unobservable.json().size(); ++i)
      out += "<li>" + html::escape(unobservable[i]["description"].text()) + "</li>";
    out += "</ul>";
  }
  out +=
      "<p>Offered, not applied: <code>keel reprocess --mission MISSION --stages "
      "ingest,refine,map --set '" +
      html::escape(c["reprocess"]["set"][0].text()) + "'</code></p>";
  return out;
}

}  // namespace
}  // namespace keel::pipeline::report_html

namespace keel::pipeline {

std::string CalibrateStage::report_html(const report_html::Ref& section,
                                        const ReportHtmlInputs&) const {
  using namespace report_html;
  if (!section["nothing_to_calibrate"].missing())
    return paragraph("Nothing to calibrate: " + section["nothing_to_calibrate"].text() + ".");
  std::string out = paragraph("Reference: " + section["reference"]["sensor"].text() + " (" +
                              section["reference"]["source"].text() + "); " +
                              section["keyframes"].text() + " keyframes.");
  const Ref candidates = section["candidates"];
  for (size_t i = 0; i < candidates.json().size(); ++i) out += candidate_section(candidates[i]);
  const Ref skipped = section["skipped_sensors"];
  for (size_t i = 0; i < skipped.json().size(); ++i)
    out +=
        paragraph("Skipped: " + skipped[i]["sensor"].text() + ": " + skipped[i]["reason"].text());
  return out;
}

}  // namespace keel::pipeline
