// report.html, stage `ingest`: the mission, every stream (count, span, measured vs nominal rate,
// gaps, points per scan, image formats) and every trajectory (poses, span, path length).
#include "worker/pipeline/html_text.h"
#include "worker/pipeline/report_html_parts.h"

namespace keel::pipeline::report_html {

namespace {

std::string per_scan(const Ref& sensor) {
  const Ref per_scan = sensor["points"]["per_scan"];
  if (per_scan.missing()) return "&#8212;";
  return per_scan["min"].cell() + " / " + per_scan["mean"].cell() + " / " + per_scan["max"].cell();
}

}  // namespace

std::string ingest_section(const Ref& stage) {
  std::string out;
  const Ref mission = stage["mission"];
  Table m{"ingest-mission", "Mission", {"", ""}, {}};
  for (const auto& item : mission.json().items())
    m.rows.push_back({html::escape(item.key()), mission[item.key()].cell()});
  out += render(m);

  Table s{
      "ingest-sensors",
      "Streams",
      {"sensor", "type", "source", "records", "duration", "rate measured", "rate nominal", "gaps",
       "longest interval", "points total", "points per scan min / mean / max", "extrinsic"},
      {}};
  const Ref sensors = stage["sensors"];
  for (const auto& item : sensors.json().items()) {
    const Ref r = sensors[item.key()];
    s.rows.push_back({html::escape(item.key()), r["type"].cell(), r["source"].cell(),
                      r["count"].cell(), r["duration_s"].cell("s"),
                      r["rate_hz_measured"].cell("Hz"), r["rate_hz_nominal"].cell("Hz"),
                      r["gaps"]["count"].cell(), r["gaps"]["longest_interval_s"].cell("s"),
                      r["points"]["total"].cell(), per_scan(r), r["extrinsic"].cell()});
  }
  out += render(s);

  Table t{"ingest-trajectories",
          "Trajectories",
          {"trajectory", "source", "poses", "duration", "rate", "path length"},
          {}};
  const Ref trajectories = stage["trajectories"];
  for (const auto& item : trajectories.json().items()) {
    const Ref r = trajectories[item.key()];
    t.rows.push_back({html::escape(item.key()), r["source"].cell(), r["count"].cell(),
                      r["duration_s"].cell("s"), r["rate_hz_measured"].cell("Hz"),
                      r["path_length_m"].cell("m")});
  }
  out += render(t);
  out += "<p>Loop closures: " + stage["loop_closures"].cell() + "</p>";
  return out + string_list(stage["warnings"], "Warnings");
}

}  // namespace keel::pipeline::report_html
