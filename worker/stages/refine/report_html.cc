// report.html, stage `refine`: Table II of seed 000 (ATE and RPE of the MAP poses and of the
// refinement without and with DVL, side by side), ATE over time (trajectories.json), the DVL
// scale s_d and the DVL-IMU rotation with their sigma, the solver and its inputs.
#include "worker/stages/refine/stage.h"

#include <cmath>

#include "worker/pipeline/html_text.h"
#include "worker/pipeline/report_html_parts.h"
#include "worker/pipeline/svg_plot.h"

namespace keel::pipeline::report_html {

namespace {

struct Column {
  const char* key;
  const char* title;
};
constexpr Column kColumns[] = {{"map", "MAP poses (recorded)"},
                               {"refined_without_dvl", "refined without DVL"},
                               {"refined_with_dvl", "refined with DVL"}};

struct Row {
  const char* title;
  const char* error;      // ate | rpe
  const char* quantity;   // translation_m | rotation_deg
  const char* statistic;  // rmse, mean, ...
  const char* unit;
};
constexpr Row kRows[] = {
    {"ATE translation RMSE", "ate", "translation_m", "rmse", "m"},
    {"ATE translation mean", "ate", "translation_m", "mean", "m"},
    {"ATE translation median", "ate", "translation_m", "median", "m"},
    {"ATE translation std", "ate", "translation_m", "std", "m"},
    {"ATE translation max", "ate", "translation_m", "max", "m"},
    {"ATE rotation RMSE", "ate", "rotation_deg", "rmse", "deg"},
    {"ATE rotation max", "ate", "rotation_deg", "max", "deg"},
    {"ATE poses", "ate", "translation_m", "count", ""},
    {"RPE translation RMSE", "rpe", "translation_m", "rmse", "m"},
    {"RPE translation mean", "rpe", "translation_m", "mean", "m"},
    {"RPE translation max", "rpe", "translation_m", "max", "m"},
    {"RPE rotation RMSE", "rpe", "rotation_deg", "rmse", "deg"},
    {"RPE rotation max", "rpe", "rotation_deg", "max", "deg"},
    {"RPE pairs", "rpe", "translation_m", "count", ""},
};

std::string table_ii(const Ref& evaluation) {
  const Ref table = evaluation["table"];
  Table t{"refine-table-ii",
          "Table II (seed 000): error against " + evaluation["ground_truth"].text(),
          {""},
          {}};
  for (const auto& c : kColumns) t.head.push_back(html::escape(c.title));
  for (const auto& r : kRows) {
    std::vector<std::string> row = {html::escape(r.title)};
    for (const auto& c : kColumns) {
      const Ref cell = table[c.key][r.error][r.quantity][r.statistic];
      const Ref error = table[c.key][r.error]["error"];
      row.push_back(!error.missing()         ? html::escape(error.text())
                    : table[c.key].missing() ? "not computed"
                                             : cell.cell(r.unit));
    }
    t.rows.push_back(std::move(row));
  }
  std::string out = render(t);
  out += "<p>ATE: " + html::escape(evaluation["ate_method"].text()) +
         ". RPE: " + html::escape(evaluation["rpe_method"].text()) + ".</p>";
  std::string reductions;
  for (const auto& [key, what] :
       {std::pair{"ate_reduction_with_dvl_vs_map_percent", "with DVL"},
        std::pair{"ate_reduction_without_dvl_vs_map_percent", "without DVL"}})
    if (!evaluation[key].missing())
      reductions +=
          std::string(reductions.empty() ? "" : "; ") + what + " " + evaluation[key].cell("%");
  if (!reductions.empty())
    out += "<p>ATE RMSE reduction against the MAP poses: " + reductions + "</p>";

  std::vector<std::string> names;
  std::vector<svg::BarGroup> groups = {{"ATE translation RMSE (m)", {}},
                                       {"RPE translation RMSE (m)", {}}};
  for (const auto& c : kColumns) {
    if (table[c.key].missing()) continue;
    names.push_back(c.title);
    groups[0].values.push_back(table[c.key]["ate"]["translation_m"]["rmse"].number());
    groups[1].values.push_back(table[c.key]["rpe"]["translation_m"]["rmse"].number());
  }
  out += figure(svg::bar_chart({"ATE and RPE (translation RMSE)", {""}, {"m"}}, names, groups),
                "Table II's translation RMSE per estimate.");
  return out;
}

// ATE over time: each trajectory of trajectories.json that has per-pose errors.
std::string ate_over_time(const nlohmann::json& trajectories) {
  if (!trajectories.is_object() || !trajectories.contains("trajectories")) return "";
  std::vector<svg::Series> series;
  double t0 = NAN;
  // In Table II's column order, so each estimate has the same colour as in the bar chart.
  for (const char* name : {"recorded", "refined_no_dvl", "refined"})
    for (const auto& t : trajectories["trajectories"]) {
      if (!t.is_object() || t.value("name", "") != name || !t.contains("ate_m") || !t.contains("t"))
        continue;
      svg::Series s{t.value("name", std::string("?")), {}, {}};
      for (size_t i = 0; i < t["t"].size() && i < t["ate_m"].size(); ++i) {
        const double time = t["t"][i].is_number() ? t["t"][i].get<double>() : NAN;
        if (std::isnan(t0) && std::isfinite(time)) t0 = time;
        s.x.push_back(time);
        s.y.push_back(t["ate_m"][i].is_number() ? t["ate_m"][i].get<double>() : NAN);
      }
      series.push_back(std::move(s));
    }
  if (series.empty()) return "";
  for (auto& s : series)
    for (double& x : s.x) x -= t0;
  return heading("ATE over time", "refine-ate-over-time") +
         figure(svg::line_chart({"ATE per pose", {"time since the first pose (s)"}, {"m"}, 900},
                                series),
                "Translation error of each pose after the report's SE(3) alignment "
                "(trajectories.json, ate_m).");
}

std::string calibration(const Ref& dvl) {
  if (dvl.missing()) return paragraph("No DVL fusion: no DVL scale or rotation estimated.");
  const Ref scale = dvl["dvl_scale"];
  const Ref rotation = dvl["dvl_rotation"];
  std::string out = heading("DVL scale s_d and DVL-IMU rotation", "refine-dvl");
  Table s{"refine-dvl-scale", "DVL scale s_d (Eq. 8)", {"estimated", "value", "sigma", "true"}, {}};
  s.rows.push_back({scale["estimated"].cell(), scale["value"].cell(), scale["sigma"].cell(),
                    scale["true"].cell()});
  out += render(s);
  Table r{"refine-dvl-rotation",
          "DVL-IMU rotation (change from mission.yaml, DVL axes)",
          {"axis", "correction", "sigma", "error vs truth"},
          {}};
  const char* axes[] = {"x", "y", "z"};
  for (size_t k = 0; k < 3; ++k)
    r.rows.push_back({axes[k], rotation["correction_deg"][k].cell("deg"),
                      rotation["sigma_deg"][k].cell("deg"),
                      rotation["error_vs_truth_deg"][k].cell("deg")});
  r.rows.push_back({"q_body_dvl (x, y, z, w)", rotation["q_body_dvl_xyzw"].cell(), "", ""});
  out += render(r);

  std::vector<svg::Interval> intervals;
  svg::Interval sd{"s_d", scale["value"].number(), scale["sigma"].number(), std::nullopt};
  if (scale["true"].is_number()) sd.truth = scale["true"].number();
  out += figure(svg::interval_chart({"DVL scale s_d", {""}, {"s_d"}, 320}, {sd}),
                "Estimate with its 1-sigma interval; the true scale when truth.yaml has it.");
  const bool errors = !rotation["error_vs_truth_deg"].missing();
  for (size_t k = 0; k < 3; ++k)
    intervals.push_back({axes[k],
                         errors ? rotation["error_vs_truth_deg"][k].number()
                                : rotation["correction_deg"][k].number(),
                         rotation["sigma_deg"][k].number(),
                         errors ? std::optional<double>(0.0) : std::nullopt});
  out += figure(svg::interval_chart(
                    {errors ? "DVL-IMU rotation error vs truth" : "DVL-IMU rotation correction",
                     {""},
                     {"deg"},
                     420},
                    intervals),
                errors ? "Rotation error per axis with its 1-sigma interval (truth at 0)."
                       : "Change from mission.yaml per axis with its 1-sigma interval.");
  Table gaps{"refine-dvl-gaps", "DVL gaps", {"", ""}, {}};
  for (const auto& item : dvl["gaps"].json().items())
    gaps.rows.push_back({html::escape(item.key()), dvl["gaps"][item.key()].cell()});
  return out + render(gaps);
}

std::string solver(const Ref& stage) {
  Table t{"refine-solver", "Solver", {"", "with the written trajectory"}, {}};
  const Ref with = stage["solver"];
  const Ref without = stage["solver_without_dvl"];
  if (!without.missing()) t.head.push_back("without DVL (Table II)");
  for (const auto& [key, unit] :
       {std::pair{"iterations", ""}, std::pair{"initial_cost", ""}, std::pair{"final_cost", ""},
        std::pair{"converged", ""}, std::pair{"solve_time_s", "s"},
        std::pair{"covariance_time_s", "s"}, std::pair{"total_time_s", "s"},
        std::pair{"keyframes", ""}, std::pair{"pseudo_samples", ""},
        std::pair{"covariance_ok", ""}}) {
    std::vector<std::string> row = {key, with[key].cell(unit)};
    if (!without.missing()) row.push_back(without[key].cell(unit));
    t.rows.push_back(row);
  }
  for (const auto& item : with["factors"].json().items()) {
    std::vector<std::string> row = {"factors: " + html::escape(item.key()),
                                    with["factors"][item.key()].cell()};
    if (!without.missing()) row.push_back(without["factors"][item.key()].cell());
    t.rows.push_back(row);
  }
  std::string out = render(t);
  out += "<p>" + html::escape(stage["solves"].text()) +
         ". Degenerate keyframes: " + stage["degenerate_keyframes"]["count"].cell() + ".</p>";
  return out;
}

std::string refine_section(const Ref& stage, const nlohmann::json& trajectories) {
  std::string out;
  const Ref evaluation = stage["evaluation"];
  if (evaluation.missing())
    out += paragraph("The mission has no ground truth: no ATE or RPE (Table II).");
  else
    out += heading("Accuracy (Table II)", "refine-accuracy") + table_ii(evaluation);
  out += ate_over_time(trajectories);
  out += calibration(stage["dvl"]);
  out += heading("Solver") + solver(stage);
  const Ref inputs = stage["inputs"];
  Table in{"refine-inputs", "Inputs", {"", ""}, {}};
  in.rows.push_back({"keyframes used", inputs["keyframes"]["used"].cell()});
  in.rows.push_back({"keyframes recorded", inputs["keyframes"]["recorded"].cell()});
  in.rows.push_back({"odometry", inputs["odometry"]["source"].cell()});
  in.rows.push_back({"odometry edges", inputs["odometry"]["edges"].cell()});
  in.rows.push_back({"loop closures", inputs["loop_closures"]["count"].cell()});
  in.rows.push_back({"IMU samples", inputs["imu"]["samples"].cell()});
  in.rows.push_back({"DVL samples", inputs["dvl"]["samples"].cell()});
  out += render(in);
  return out + string_list(stage["warnings"], "Warnings");
}

}  // namespace

}  // namespace keel::pipeline::report_html

namespace keel::pipeline {

std::string RefineStage::report_html(const report_html::Ref& section,
                                     const ReportHtmlInputs& inputs) const {
  return report_html::refine_section(section, inputs.trajectories);
}

}  // namespace keel::pipeline
