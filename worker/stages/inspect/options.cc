#include "worker/stages/inspect/options.h"

#include "worker/pipeline/option_table.h"
#include "worker/stages/inspect/stage.h"

namespace keel::pipeline {

namespace {

using O = InspectStageOptions;
using Algorithm = inspect::InspectOptions;

// A row for a member of the algorithm's options (InspectStageOptions::inspect).
template <typename T>
OptionRow<O> algorithm(const char* name, T Algorithm::*field, Check<T> check, OptionDoc doc) {
  OptionRow<Algorithm> row = option(name, field, std::move(check), std::move(doc));
  return {row.name, row.type, row.doc,
          [read = row.read](O& o, const nlohmann::json& value, const std::string& path) {
            read(o.inspect, value, path);
          },
          [write = row.write](const O& o) { return write(o.inspect); }};
}

// The rows' order is that of the docs' table and of the "known" list in an unknown option's
// error.
const OptionTable<O>& table() {
  static const OptionTable<O> table(
      "inspect",
      {
          algorithm(
              "tau_m", &Algorithm::tau_m, at_least(0),
              {"m",
               "≥ 0: floor of the threshold τ of Algorithm 1 line 6: a feature is clustered when "
               "its structural deviation |h| > τ, with τ = max(`tau_m`, |b| + `tau_noise_sigmas` "
               "· σ_h) (b and σ_h: the median of h and its spread about it, see "
               "`tau_noise_sigmas`; `tau_m` alone when `tau_noise_sigmas` is 0)",
               "seed 001 Sec. 4.2.2: τ = 0 preferred (Fig. 21(b)), 0.06 m where false positives "
               "matter (Fig. 21(c))"}),
          algorithm(
              "tau_noise_sigmas", &Algorithm::tau_noise_sigmas, at_least(0),
              {"",
               "≥ 0: how many noise sigmas τ must clear beyond the reconstruction's offset from "
               "the model: τ = max(`tau_m`, |b| + `tau_noise_sigmas` · σ_h), where b = median h "
               "and σ_h = 1.4826 · median |h − b| over the landmarks the BA labelled on the model "
               "(λ = 1), reported as `deviation_bias_m`, `deviation_noise_sigma_m` and (the τ "
               "used) `tau_m`. 0: τ = `tau_m` exactly (the paper)",
               "beyond the paper: at τ = 0 the BA's noise on clean hull clusters into shapes; "
               "clean-hull features reached 5 σ on keel-sim hauv-hull, hence 8. About the "
               "median, not 0: on a hull with 30 fouling patches (`keel-sim --set "
               "hull.fouling_patches=30`) features on the patches' flanks, labelled on the "
               "model, pull the model outwards (b = −1.0 to −1.3 mm) and the MAD about 0 read "
               "σ_h 1.3-1.5x too high: τ 2.0-2.4 cm missed 9 of the 90 patches over seeds 1-3, "
               "τ 1.7-1.9 cm misses 4 (each with at most 3 landmarks above τ), still no shape on "
               "clean hull; the clean hull's τ is unchanged (b ≈ 0.1 mm)"}),
          algorithm("dbscan_eps_m", &Algorithm::dbscan_eps_m, greater_than(0),
                    {"m", "> 0: DBSCAN radius over (f_x, f_y, d) (Algorithm 1 line 11)",
                     "beyond the paper (it gives none): below 2 `alpha_m`, so every DBSCAN link "
                     "is shorter than the alpha disc's diameter; 0.14 rather than 0.12 finds the "
                     "sparsest-textured patch of seeds 1-10 (below)"}),
          algorithm("dbscan_min_pts", &Algorithm::dbscan_min_pts, int_at_least(1),
                    {"", "≥ 1: DBSCAN minimum points per cluster, the point itself included",
                     "seed 001 Sec. 4.2.1 (\"we choose 3\")"}),
          algorithm(
              "min_shape_views", &Algorithm::min_shape_views, int_at_least(1),
              {"",
               "≥ 1: a shape (Algorithm 1's per-view detections merged into one object) is kept "
               "only when at least this many views detected it; the others are neither fused "
               "into `mesh_remeshed` nor listed in shapes.json (the report counts them, "
               "`shapes_rejected_few_views`). 1: every detection, as in the paper",
               "beyond the paper, and not tuned to a survey: the standard a monocular feature "
               "must meet to be triangulated at all (`ba` `triangulation.min_monocular_views` = "
               "3). A cluster seen in one or two views can be three features whose "
               "reconstruction noise agrees there (issue 18: a 3-feature shape 3 cm behind the "
               "model, in one view); a structure on the hull stays in view for ~10 images of a "
               "lane (2 Hz, 0.25 m/s, a footprint over 1 m wide). See \"Detection on unseen "
               "surveys\" below"}),
          algorithm("alpha_m", &Algorithm::alpha_m, greater_than(0),
                    {"m", "> 0: radius of the 2.5D alpha shape's disc (CGAL takes its square)",
                     "seed 001 Sec. 3.2 (\"a fixed value of 12 cm\")"}),
          algorithm("view_range_m", &Algorithm::view_range_m, greater_than(0),
                    {"m",
                     "> 0: `nearby_vertices()` of Algorithm 2: CAD vertices within this of the "
                     "camera are candidates for moving",
                     "seed 001 Sec. 3.3 (\"we conservatively use 5 m\")"}),
          algorithm("max_behind_vertex_m", &Algorithm::max_behind_vertex_m, at_least(0),
                    {"m",
                     "≥ 0: how far beyond the CAD vertex the camera→vertex ray may meet a shape. "
                     "0: only structure in front of the surface (protrusions) is fused, as in "
                     "the paper; > 0 also fuses dents and missing material (h < −τ)",
                     "0 is seed 001 Sec. 3.3; > 0 is ours"}),
          algorithm("top_site_noise_sigmas", &Algorithm::top_site_noise_sigmas, at_least(0),
                    {"",
                     "≥ 0: a shape's `height_sampling_sigma_m` (shapes.json: how far its top may "
                     "lie beyond its highest feature) counts heights within this many "
                     "`deviation_noise_sigma_m` of a higher one as one sampling site (a texture "
                     "blob gives several features at one height)",
                     "beyond the paper; 3 σ: two heights closer than that cannot be told apart. "
                     "See \"How far a top may lie beyond the highest feature\" below"}),
          algorithm("top_spacings", &Algorithm::top_spacings, int_at_least(1),
                    {"",
                     "≥ 1: `height_sampling_sigma_m` is the mean of this many spacings between "
                     "the highest sites",
                     "beyond the paper; see below"}),
          option("draco_position_bits", &O::draco_position_bits, int_in_range(1, 30),
                 {"",
                  "in [1, 30]: Draco position quantization of `mesh_remeshed.drc`: error ≤ √3/2 · "
                  "extent / (2¹⁶ − 1), 0.4 mm on a 30 m hull",
                  "beyond the paper"}),
          option("draco_field_bits", &O::draco_field_bits, int_in_range(0, 30),
                 {"",
                  "in [0, 30]: quantization of the per-vertex `deviation` field; 0 stores it "
                  "losslessly",
                  "beyond the paper"}),
          option("write_ply", &O::write_ply,
                 {"", "also write `mesh_remeshed.ply` (same `deviation` field)", ""}),
          option("match_distance_m", &O::match_distance_m, at_least(0),
                 {"m",
                  "≥ 0: with truth.yaml's `foreign_objects`: a shape matches an object when its "
                  "centroid is within the object's radius plus this of the object's centre",
                  "evaluation only"}),
      });
  return table;
}

}  // namespace

InspectStageOptions InspectStageOptions::from_json(const nlohmann::json& options) {
  return table().from_json(options);
}

const OptionsSchema& InspectStage::options() const { return table(); }

}  // namespace keel::pipeline
