// report.html, stage `ba` (seed 001): per BA mode the iterations, times, costs and x_gM against
// truth; the lambda = 1 fraction per iteration (Fig. 16), the cost per iteration (Fig. 17), the
// DVL range residuals after GICP and after the BA (Fig. 18c).
#include <cmath>

#include "worker/stages/ba/stage.h"

#include "worker/pipeline/html_text.h"
#include "worker/pipeline/report_html_parts.h"
#include "worker/pipeline/svg_plot.h"

namespace keel::pipeline {

using namespace report_html;

namespace {

std::vector<double> iterations_of(size_t n) {
  std::vector<double> x(n);
  for (size_t i = 0; i < n; ++i) x[i] = static_cast<double>(i);
  return x;
}

// The residual histogram of residual_stats: bins of bin_m from first_edge_m.
svg::Histogram residual_histogram(const std::string& name, const Ref& stats) {
  const Ref h = stats["histogram"];
  svg::Histogram out{name, {}, h["counts"].numbers()};
  const double first = h["first_edge_m"].number(), bin = h["bin_m"].number();
  for (size_t i = 0; i <= out.counts.size(); ++i) out.edges.push_back(first + bin * i);
  if (out.counts.empty()) out.edges.clear();
  return out;
}

std::string modes_table(const Ref& modes) {
  Table t{"ba-modes", "BA modes (seed 001 Sec. 4)", {""}, {}};
  for (const auto& item : modes.json().items()) t.head.push_back(html::escape(item.key()));
  struct Row {
    const char* title;
    std::vector<const char*> path;
    const char* unit;
  };
  const std::vector<Row> rows = {
      {"iterations", {"iterations"}, ""},
      {"rejected steps", {"unsuccessful_steps"}, ""},
      {"solve time", {"solve_time_s"}, "s"},
      {"solve CPU time", {"solve_cpu_s"}, "s"},
      {"initial cost", {"initial_cost"}, ""},
      {"final cost", {"final_cost"}, ""},
      {"converged", {"converged"}, ""},
      {"termination", {"termination"}, ""},
      {"landmarks", {"landmarks"}, ""},
      {"landmarks with lambda = 1", {"landmarks_lambda1"}, ""},
      {"DVL residual sigma after GICP", {"dvl_residuals_gicp", "sigma_m"}, "m"},
      {"DVL residual sigma after BA", {"dvl_residuals_final", "sigma_m"}, "m"},
      {"DVL residual robust sigma after GICP", {"dvl_residuals_gicp", "robust_sigma_m"}, "m"},
      {"DVL residual robust sigma after BA", {"dvl_residuals_final", "robust_sigma_m"}, "m"},
      {"DVL residual median after BA", {"dvl_residuals_final", "percentiles_m", "p50"}, "m"},
      {"x_gM translation error vs truth", {"T_world_model_vs_truth", "translation_error_m"}, "m"},
      {"x_gM error along model x, y, z",
       {"T_world_model_vs_truth", "translation_error_model_axes_m"},
       "m"},
      {"x_gM rotation error vs truth", {"T_world_model_vs_truth", "rotation_error_deg"}, "deg"},
      {"x_gM translation sigma along model x, y, z",
       {"T_world_model_translation_sigma_model_axes_m"},
       "m"},
      {"x_gM translation (world)", {"T_world_model", "translation"}, "m"},
      {"x_gM rotation (x, y, z, w)", {"T_world_model", "rotation_xyzw"}, ""},
  };
  for (const auto& r : rows) {
    std::vector<std::string> row = {html::escape(r.title)};
    for (const auto& item : modes.json().items()) {
      Ref value = modes[item.key()];
      for (const char* key : r.path) value = value[key];
      row.push_back(value.cell(r.unit));
    }
    t.rows.push_back(row);
  }
  return render(t);
}

std::string per_iteration_figures(const Ref& modes) {
  std::vector<svg::Series> lambda, cost;
  for (const auto& item : modes.json().items()) {
    const std::vector<double> l = modes[item.key()]["lambda1_fraction_per_iteration"].numbers();
    const std::vector<double> c = modes[item.key()]["cost_per_iteration"].numbers();
    lambda.push_back({item.key(), iterations_of(l.size()), l, true});
    cost.push_back({item.key(), iterations_of(c.size()), c, true});
  }
  return figure(svg::line_chart(
                    {"Fig. 16: fraction of landmarks with lambda = 1", {"iteration"}, {"fraction"}},
                    lambda),
                "Share of landmarks labelled on the model (Eq. 7) after each iteration.") +
         figure(
             svg::line_chart({"Fig. 17: cost per iteration", {"iteration"}, {"cost", true}}, cost),
             "Ceres cost after each iteration (log scale).");
}

std::string residual_figures(const Ref& modes) {
  std::string out;
  Table t{"ba-dvl-residuals",
          "DVL range residuals (Fig. 18)",
          {"mode", "state", "beams", "mean", "sigma", "robust sigma", "p05", "p50", "p95",
           "below range", "above range"},
          {}};
  for (const auto& item : modes.json().items()) {
    const Ref mode = modes[item.key()];
    std::vector<svg::Histogram> histograms = {
        residual_histogram("after GICP", mode["dvl_residuals_gicp"]),
        residual_histogram("after BA (" + item.key() + ")", mode["dvl_residuals_final"])};
    out += figure(svg::histogram_chart({"Fig. 18(c): DVL residuals, " + item.key(),
                                        {"measured - predicted range (m)"},
                                        {"beams"}},
                                       histograms, false),
                  "Histogram of each DVL beam's range residual against the CAD mesh.");
    for (const auto& [state, key] : {std::pair{"after GICP", "dvl_residuals_gicp"},
                                     std::pair{"after BA", "dvl_residuals_final"}}) {
      const Ref s = mode[key];
      t.rows.push_back({html::escape(item.key()), state, s["count"].cell(), s["mean_m"].cell("m"),
                        s["sigma_m"].cell("m"), s["robust_sigma_m"].cell("m"),
                        s["percentiles_m"]["p5"].cell("m"), s["percentiles_m"]["p50"].cell("m"),
                        s["percentiles_m"]["p95"].cell("m"), s["histogram"]["below"].cell(),
                        s["histogram"]["above"].cell()});
    }
  }
  return out + render(t);
}

}  // namespace

std::string BaStage::report_html(const Ref& stage, const ReportHtmlInputs&) const {
  std::string out;
  const Ref modes = stage["modes"];
  out += heading("Modes", "ba-modes-heading") + modes_table(modes);
  out += "<p>Artifacts from mode " + stage["solution_mode"].cell() + ".</p>";
  out += heading("Per iteration (Figs. 16 and 17)", "ba-iterations") + per_iteration_figures(modes);
  out += heading("DVL residuals (Fig. 18)", "ba-residuals") + residual_figures(modes);
  const Ref gicp = stage["gicp"];
  Table g{"ba-inputs", "Inputs and initialisation", {"", ""}, {}};
  g.rows.push_back({"keyframes", stage["input"]["keyframes"].cell()});
  g.rows.push_back({"tracks", stage["input"]["tracks_source"].cell()});
  g.rows.push_back({"tracks in", stage["tracks_in"].cell()});
  g.rows.push_back({"landmarks triangulated", stage["landmarks_triangulated"].cell()});
  g.rows.push_back({"DVL ranges in / used",
                    stage["dvl_ranges_in"].cell() + " / " + stage["dvl_ranges_used"].cell()});
  g.rows.push_back({"GICP converged", gicp["converged"].cell()});
  g.rows.push_back({"GICP fitness", gicp["fitness_m2"].cell("m^2")});
  g.rows.push_back({"GICP x_gM translation error vs truth",
                    gicp["T_world_model_vs_truth"]["translation_error_m"].cell("m")});
  g.rows.push_back({"CAD mesh", stage["input"]["cad_mesh"].cell()});
  return out + render(g);
}

}  // namespace keel::pipeline
