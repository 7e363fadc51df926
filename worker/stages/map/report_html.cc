// report.html, stage `map`: Table V of seed 000 (density, roughness, planarity of the SLAM map
// and the inspection maps, Eqs. 23-26) with the metric distributions as histograms, the points
// per sensor and per filter (Table IV chains), the files, the poses and the timing.
#include <cmath>

#include "worker/pipeline/html_text.h"
#include "worker/pipeline/report_html_parts.h"
#include "worker/pipeline/svg_plot.h"
#include "worker/stages/map/stage.h"

namespace keel::pipeline::report_html {

namespace {

struct Metric {
  const char* row;  // Table V's row name
  const char* key;  // the distribution's key in metrics.maps.<map>
  const char* title;
  const char* unit;
};
constexpr Metric kMetrics[] = {
    {"surface_density", "surface_density_per_m2", "surface density (Eq. 23)", "points/m^2"},
    {"roughness", "roughness_m", "roughness (Eq. 24)", "m"},
    {"planarity", "planarity", "planarity (Eqs. 25-26)", "1"}};

std::string table_v(const Ref& metrics) {
  const Ref table = metrics["table_v"];
  const Ref columns = table["columns"];
  Table t{"map-table-v",
          "Table V (seed 000): mean per map, within " + metrics["radius_m"].text() +
              " m of each of at most " + metrics["max_query_points"].text() + " query points",
          {"metric", "unit"},
          {}};
  for (const auto& c : columns.json()) t.head.push_back(html::escape(c.get<std::string>()));
  const Ref rows = table["rows"];
  for (size_t i = 0; i < rows.json().size(); ++i) {
    std::vector<std::string> row = {rows[i]["metric"].cell(), rows[i]["unit"].cell()};
    for (const auto& c : columns.json()) row.push_back(rows[i][c.get<std::string>()].cell());
    t.rows.push_back(row);
  }
  std::string out = render(t);
  const Ref ratios = table["ratios"];
  if (ratios.missing()) return out;
  Table r{"map-table-v-ratios",
          "Inspection map (" + table["inspection_map"].text() + ") against the SLAM map",
          {"", "this job", "seed 000 Table V", "inspection map better"},
          {}};
  const Ref paper = ratios["paper_table_v"];
  const Ref better = table["inspection_beats_slam"];
  r.rows.push_back({"density factor", ratios["density_factor"].cell(),
                    paper["density_factor"].cell(), better["surface_density"].cell()});
  r.rows.push_back({"roughness change", ratios["roughness_change_percent"].cell("%"),
                    paper["roughness_change_percent"].cell("%"), better["roughness"].cell()});
  r.rows.push_back({"planarity change", ratios["planarity_change_percent"].cell("%"),
                    paper["planarity_change_percent"].cell("%"), better["planarity"].cell()});
  return out + render(r);
}

std::string distributions(const Ref& maps) {
  std::string out;
  for (const auto& m : kMetrics) {
    std::vector<svg::Histogram> histograms;
    Table t{std::string("map-distribution-") + m.row,
            std::string("Distribution of ") + m.title,
            {"map", "count", "undefined", "mean", "std", "min", "p05", "median", "p95", "max"},
            {}};
    for (const auto& item : maps.json().items()) {
      const Ref d = maps[item.key()][m.key];
      histograms.push_back(
          {item.key(), d["histogram_edges"].numbers(), d["histogram_counts"].numbers()});
      std::vector<std::string> row = {html::escape(item.key())};
      for (const char* key :
           {"count", "undefined", "mean", "std", "min", "p05", "median", "p95", "max"})
        row.push_back(d[key].cell());
      t.rows.push_back(row);
    }
    out += figure(svg::histogram_chart({m.title, {std::string(m.unit)}, {"fraction of points"}},
                                       histograms, true),
                  "Histogram of each map's values (fraction of its query points per bin).");
    out += render(t);
  }
  return out;
}

// Map points per sensor and the combined map, with their files.
std::string points_per_sensor(const Ref& stage) {
  Table t{"map-points",
          "Points per map",
          {"map", "type", "scans", "points in", "map points", "Draco bytes", "bytes per point",
           "Draco max position error", "PLY bytes", "preview points"},
          {}};
  svg::BarGroup bars{"", {}};
  std::vector<svg::BarGroup> groups;
  const Ref sensors = stage["sensors"];
  for (const auto& item : sensors.json().items()) {
    const Ref s = sensors[item.key()];
    const Ref map = s["map"];
    t.rows.push_back({html::escape(item.key()), s["type"].cell(), s["stats"]["scans"].cell(),
                      s["stats"]["points_in"].cell(), map["points"].cell(),
                      map["draco"]["bytes"].cell(), map["draco"]["bytes_per_point"].cell(),
                      map["draco"]["max_position_error_m"].cell("m"), map["ply"]["bytes"].cell(),
                      map["preview"]["points"].cell()});
    groups.push_back({item.key(), {s["stats"]["points_in"].number(), map["points"].number()}});
  }
  const Ref combined = stage["combined"];
  t.rows.push_back({"combined", "", "", "", combined["points"].cell(),
                    combined["draco"]["bytes"].cell(), combined["draco"]["bytes_per_point"].cell(),
                    combined["draco"]["max_position_error_m"].cell("m"),
                    combined["ply"]["bytes"].cell(), combined["preview"]["points"].cell()});
  groups.push_back({"combined", {NAN, combined["points"].number()}});
  return render(t) + figure(svg::bar_chart({"Points per sensor", {""}, {"points", true}},
                                           {"scan points in", "map points"}, groups),
                            "Points read from the scans and points kept in each map (log scale).");
}

// Each filter of the three stages of a sensor's chain (Fig. 5): points in and out.
std::string points_per_filter(const Ref& stage) {
  std::string out;
  const Ref sensors = stage["sensors"];
  for (const auto& item : sensors.json().items()) {
    const Ref stats = sensors[item.key()]["stats"];
    if (stats.missing()) continue;
    Table t{"map-filters-" + item.key(),
            "Filters of " + item.key(),
            {"stage", "applications", "filter", "points in", "points out"},
            {}};
    std::vector<svg::BarGroup> groups;
    for (const char* chain : {"scan_stage", "intermediary_stage", "final_stage"}) {
      const Ref filters = stats[chain]["filters"];
      for (size_t i = 0; i < filters.json().size(); ++i) {
        t.rows.push_back({chain, stats[chain]["applications"].cell(), filters[i]["filter"].cell(),
                          filters[i]["points_in"].cell(), filters[i]["points_out"].cell()});
        groups.push_back({std::string(chain).substr(0, 1) + ": " + filters[i]["filter"].text(),
                          {filters[i]["points_in"].number(), filters[i]["points_out"].number()}});
      }
    }
    out += render(t);
    out += figure(svg::bar_chart({"Points per filter: " + item.key(), {""}, {"points", true}, 900},
                                 {"in", "out"}, groups),
                  "s: per scan, i: per intermediary map, f: final map (log scale).");
  }
  return out;
}

std::string timing(const Ref& timing) {
  Table t{"map-timing", "Timing", {"", ""}, {}};
  for (const auto& item : timing.json().items())
    t.rows.push_back({html::escape(item.key()), timing[item.key()].cell()});
  return render(t);
}

std::string map_section(const Ref& stage) {
  std::string out;
  const Ref metrics = stage["metrics"];
  out += heading("Map quality (Table V)", "map-quality") + table_v(metrics);
  out += distributions(metrics["maps"]);
  out += heading("Points per sensor", "map-points-heading") + points_per_sensor(stage);
  out += heading("Points per filter", "map-filters") + points_per_filter(stage);
  const Ref poses = stage["poses"];
  out += heading("Poses") + "<p>" + poses["source"].cell() + "; " +
         poses["trajectory"]["poses"].cell() + " poses over " +
         poses["trajectory"]["duration_s"].cell("s") + ".</p>";
  const Ref slam = stage["slam_map"];
  if (!slam.missing())
    out += "<p>SLAM-map baseline: " + slam["sensor"].cell() + ", " + slam["keyframes_used"].cell() +
           " of " + slam["keyframes"].cell() + " keyframes, " + slam["points"].cell() +
           " points.</p>";
  out += heading("Timing") + timing(stage["timing"]);
  out += string_list(stage["warnings"], "Warnings");
  const Ref skipped = stage["skipped_sensors"];
  for (size_t i = 0; i < skipped.json().size(); ++i)
    out +=
        "<p>Skipped: " + skipped[i]["sensor"].cell() + ": " + skipped[i]["reason"].cell() + "</p>";
  return out;
}

}  // namespace
}  // namespace keel::pipeline::report_html

namespace keel::pipeline {

std::string MapStage::report_html(const report_html::Ref& section, const ReportHtmlInputs&) const {
  return report_html::map_section(section);
}

}  // namespace keel::pipeline
