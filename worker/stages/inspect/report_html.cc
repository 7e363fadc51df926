// report.html, stage `inspect` (seed 001 Sec. 3): the detected shapes (centroid, extent,
// measured height, views) and, with ground truth, each foreign object found or missed.
#include "worker/pipeline/html_text.h"
#include "worker/pipeline/report_html_parts.h"
#include "worker/stages/inspect/stage.h"

namespace keel::pipeline {

using namespace report_html;

std::string InspectStage::report_html(const Ref& stage, const ReportHtmlInputs&) const {
  std::string out;
  Table s{"inspect-shapes",
          "Detected shapes (seed 001 Sec. 3)",
          {"shape", "centroid x, y, z (m)", "extent x, y, z (m)", "measured height",
           "mean deviation", "views", "landmarks", "detections"},
          {}};
  const Ref shapes = stage["shapes"];
  for (size_t i = 0; i < shapes.json().size(); ++i) {
    const Ref shape = shapes[i];
    s.rows.push_back({shape["id"].cell(), shape["centroid_world"].cell(), shape["extent_m"].cell(),
                      shape["height_m"].cell("m"), shape["mean_deviation_m"].cell("m"),
                      shape["views"].cell(), shape["landmarks"].cell(),
                      shape["detections"].cell()});
  }
  out += render(s);
  out += "<p>Threshold tau " + stage["tau_m"].cell("m") + " (noise sigma " +
         stage["deviation_noise_sigma_m"].cell("m") + ", bias " +
         stage["deviation_bias_m"].cell("m") + "); " + stage["views"].cell() + " views, " +
         stage["views_with_shapes"].cell() + " with shapes; " + stage["vertices_moved"].cell() +
         " CAD vertices moved.</p>";
  const Ref truth = stage["truth"];
  if (!truth.missing()) {
    out += "<p id=\"inspect-found\">Foreign objects found: " + truth["found"].cell() +
           ", missed: " + truth["missed"].cell() +
           "; shapes matching no object: " + truth["false_shapes"].cell() +
           ", extra shapes on objects: " + truth["extra_shapes_on_objects"].cell() + ".</p>";
    Table t{"inspect-truth",
            "Foreign objects of truth.yaml",
            {"object", "kind", "radius", "true height", "found", "shape", "measured height",
             "height error", "nearest shape"},
            {}};
    const Ref objects = truth["objects"];
    for (size_t i = 0; i < objects.json().size(); ++i) {
      const Ref o = objects[i];
      t.rows.push_back({std::to_string(i), o["kind"].cell(), o["radius_m"].cell("m"),
                        o["true_height_m"].cell("m"),
                        o["found"].json() == true ? "found" : "missed", o["shape_id"].cell(),
                        o["measured_height_m"].cell("m"), o["height_error_m"].cell("m"),
                        o["nearest_shape_distance_m"].cell("m")});
    }
    out += render(t) + paragraph(truth["note"].text());
  }
  return out;
}

}  // namespace keel::pipeline
