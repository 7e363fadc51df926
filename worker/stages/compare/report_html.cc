// report.html, stage `compare` (issue 16; layout in docs/artifacts.md): the two jobs, the
// registration of B onto A, per map the compared and significant areas with the change
// histogram (M3C2, Lague et al. 2013), the hulls' deviation change and per-shape growth table,
// and the two runs side by side (options that differ, the figures that differ most, the
// relative ATE).
#include <algorithm>
#include <cmath>

#include "worker/pipeline/html_text.h"
#include "worker/pipeline/report_html_parts.h"
#include "worker/pipeline/svg_plot.h"

namespace keel::pipeline::report_html {

namespace {

// The figures that differ most, by |relative difference|: the rest are in "Every figure".
constexpr size_t kFiguresShown = 60;

std::string registration_table(const Ref& registration) {
  const Ref T = registration["T_a_b"];
  Table t{"compare-registration", "B registered onto A on stable structure", {"", ""}, {}};
  t.rows.push_back({"map", registration["map"].cell()});
  t.rows.push_back({"translation", T["translation_m"].cell("m")});
  t.rows.push_back({"translation norm", T["translation_norm_m"].cell("m")});
  t.rows.push_back({"rotation", T["rotation_deg"].cell("deg")});
  t.rows.push_back({"rms on stable pairs", registration["rms_stable_m"].cell("m")});
  t.rows.push_back({"stable fraction", registration["stable_fraction"].cell()});
  t.rows.push_back({"iterations", registration["iterations"].cell()});
  t.rows.push_back({"converged", registration["converged"].cell()});
  return render(t);
}

std::string maps_part(const Ref& maps) {
  std::string out = heading("Maps: change along the local normal (M3C2)", "compare-maps");
  out += paragraph("Normals face " + maps["normals_face"].text() + ".");
  if (!maps["registration"].missing()) out += registration_table(maps["registration"]);
  Table t{"compare-maps-table",
          "Per map: B's change against A",
          {"map", "points A", "points B", "core points", "defined", "compared area",
           "significant area", "significant fraction", "added", "removed", "reg. error",
           "LoD95 exceeded on stable", "tiles corrected", "points/s"},
          {}};
  const Ref per_map = maps["maps"];
  for (const auto& item : per_map.json().items()) {
    const Ref m = per_map[item.key()];
    t.rows.push_back({html::escape(item.key()), m["points_a"].cell(), m["points_b"].cell(),
                      m["core_points"].cell(), m["defined_core_points"].cell(),
                      m["compared_area_m2"].cell("m^2"), m["significant_area_m2"].cell("m^2"),
                      m["significant_fraction"].cell(), m["significant_added_area_m2"].cell("m^2"),
                      m["significant_removed_area_m2"].cell("m^2"),
                      m["registration_error_m"].cell("m"),
                      m["level_of_detection"]["exceedance_on_stable"].cell(),
                      m["local_registration"]["adjusted_tiles"].cell() + " / " +
                          m["local_registration"]["tiles"].cell(),
                      m["points_per_second"].cell()});
  }
  out += render(t);
  out += paragraph(
      "LoD95 exceeded on stable: the fraction of core points on each tile's stable structure "
      "whose |M3C2| exceeds LoD95 (5 % when the 95 % level holds; reg is calibrated per tile "
      "to that). A core's change is significant when its neighbours within "
      "significance_radius_m agree.");
  for (const auto& item : per_map.json().items()) {
    const Ref tiles = per_map[item.key()]["local_registration"]["per_tile"];
    if (tiles.missing()) continue;
    Table r{
        "compare-tiles-" + item.key(),
        "Local registration per tile, " + item.key(),
        {"centre", "status", "cores", "stable cores", "noise", "fixed directions", "correction"},
        {}};
    for (size_t i = 0; i < tiles.json().size(); ++i) {
      const Ref x = tiles[i];
      r.rows.push_back({x["center_m"].cell(), x["status"].cell(), x["cores"].cell(),
                        x["stable_cores"].cell(), x["noise_m"].cell("m"),
                        x["fixed_directions"].cell(), x["correction_m"].cell("m")});
    }
    out += render(r);
  }
  for (const auto& item : per_map.json().items()) {
    const Ref h = per_map[item.key()]["change_histogram"];
    out += figure(
        svg::histogram_chart(
            {"Change histogram, " + item.key(), {"M3C2 change of B against A (m)"}, {"area (m^2)"}},
            {{item.key(), h["edges_m"].numbers(), h["area_m2"].numbers()}}, false),
        "Area of the core points per change bin; " + h["below"].text() + " below and " +
            h["above"].text() + " above the range.");
    Table d{"compare-distribution-" + item.key(),
            "Distributions, " + item.key(),
            {"", "count", "mean", "std", "min", "p05", "median", "p95", "max"},
            {}};
    for (const char* key : {"m3c2_m", "lod95_m", "c2c_m"}) {
      const Ref s = per_map[item.key()][key];
      std::vector<std::string> row = {key};
      for (const char* k : {"count", "mean", "std", "min", "p05", "median", "p95", "max"})
        row.push_back(s[k].cell());
      d.rows.push_back(row);
    }
    out += render(d);
  }
  return out;
}

std::string hull_part(const Ref& hull) {
  std::string out =
      heading("Hulls: deviation change and shape growth (model frame)", "compare-hull");
  Table s{"compare-hull-summary", "", {"", ""}, {}};
  s.rows.push_back({"x_gM difference", hull["x_gM_difference"]["translation_norm_m"].cell("m")});
  s.rows.push_back(
      {"x_gM rotation difference", hull["x_gM_difference"]["rotation_deg"].cell("deg")});
  s.rows.push_back(
      {"shapes registered by", hull["shape_registration"]["translation_norm_m"].cell("m") + " (" +
                                   hull["shape_registration"]["pairs"].cell() + " shapes agree)"});
  s.rows.push_back({"vertices", hull["vertices"].cell()});
  s.rows.push_back({"deviation change, mean", hull["deviation_change_m"]["mean"].cell("m")});
  s.rows.push_back({"deviation change, max", hull["deviation_change_m"]["max"].cell("m")});
  s.rows.push_back({"shapes A / B", hull["shapes_a"].cell() + " / " + hull["shapes_b"].cell()});
  s.rows.push_back({"kept / new / gone", hull["kept"].cell() + " / " + hull["new"].cell() + " / " +
                                             hull["gone"].cell()});
  s.rows.push_back({"significantly grown", hull["significantly_grown"].cell()});
  out += render(s);
  Table t{"compare-shapes",
          "Shapes matched across the surveys",
          {"status", "shape A", "shape B", "centroid (model, m)", "height A", "height B",
           "height growth", "sigma", "footprint growth", "sigma", "significant"},
          {}};
  const Ref shapes = hull["shapes"];
  for (size_t i = 0; i < shapes.json().size(); ++i) {
    const Ref r = shapes[i];
    t.rows.push_back({r["status"].cell(), r["shape_a"].cell(), r["shape_b"].cell(),
                      r["centroid_model_m"].cell(), r["height_a_m"].cell("m"),
                      r["height_b_m"].cell("m"), r["height_growth_m"].cell("m"),
                      r["height_growth_sigma_m"].cell("m"), r["footprint_growth_m2"].cell("m^2"),
                      r["footprint_growth_sigma_m2"].cell("m^2"), r["significant_growth"].cell()});
  }
  return out + render(t);
}

std::string runs_part(const Ref& runs) {
  std::string out = heading("The two runs side by side", "compare-runs");
  out += "<p>Same mission: " + runs["same_mission"].cell() + "; figures in both " +
         runs["figures_in_both"].cell() + ", that differ " + runs["figures_that_differ"].cell() +
         ", only in A " + runs["figures_only_in_a"].cell() + ", only in B " +
         runs["figures_only_in_b"].cell() + ".</p>";
  Table o{"compare-options", "Options that differ", {"option", "A", "B"}, {}};
  const Ref options = runs["options_differ"];
  for (size_t i = 0; i < options.json().size(); ++i)
    o.rows.push_back({options[i]["option"].cell(), options[i]["a"].cell(), options[i]["b"].cell()});
  out += render(o);

  const Ref figures = runs["figures"];
  std::vector<size_t> order;
  for (size_t i = 0; i < figures.json().size(); ++i)
    if (figures[i]["difference"].number() != 0.0) order.push_back(i);
  auto magnitude = [&](size_t i) {
    const double r = std::abs(figures[i]["relative"].number());
    return std::isfinite(r) ? r : std::abs(figures[i]["difference"].number());
  };
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t x, size_t y) { return magnitude(x) > magnitude(y); });
  if (order.size() > kFiguresShown) order.resize(kFiguresShown);
  Table f{"compare-figures",
          "The figures that differ most (all of them: Every figure of report.json)",
          {"figure", "A", "B", "B - A", "relative"},
          {}};
  for (size_t i : order)
    f.rows.push_back({figures[i]["figure"].cell(), figures[i]["a"].cell(), figures[i]["b"].cell(),
                      figures[i]["difference"].cell(), figures[i]["relative"].cell()});
  out += render(f);

  const Ref ate = runs["relative_ate"];
  Table a{"compare-relative-ate",
          "B's trajectory against A's (relative ATE)",
          {"trajectory", "alignment", "rmse", "mean", "max", "poses"},
          {}};
  for (const auto& item : ate.json().items()) {
    const Ref t = ate[item.key()];
    if (!t["error"].missing()) {
      a.rows.push_back({html::escape(item.key()), t["error"].cell(), "", "", "", ""});
      continue;
    }
    for (const char* alignment : {"ate_none", "ate_se3"}) {
      const Ref s = t[alignment]["translation_m"];
      if (s.missing()) continue;
      a.rows.push_back({html::escape(item.key()), alignment, s["rmse"].cell("m"),
                        s["mean"].cell("m"), s["max"].cell("m"), s["count"].cell()});
    }
  }
  return out + render(a);
}

}  // namespace

std::string compare_section(const Ref& stage) {
  std::string out = "<p>Job A " + stage["job_a"].cell() + " (earlier) against job B " +
                    stage["job_b"].cell() + " (later): " + stage["kind"].cell() + ".</p>";
  if (!stage["maps"].missing()) out += maps_part(stage["maps"]);
  if (!stage["hull"].missing()) out += hull_part(stage["hull"]);
  if (!stage["runs"].missing()) out += runs_part(stage["runs"]);
  return out;
}

}  // namespace keel::pipeline::report_html
