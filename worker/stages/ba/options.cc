#include "worker/stages/ba/options.h"

#include "worker/pipeline/option_table.h"
#include "worker/stages/ba/stage.h"

namespace keel::pipeline {

namespace {

using O = BaStageOptions;

// The rows' order is that of the docs' table and of the "known" list in an unknown option's
// error.
const OptionTable<O>& table() {
  static const OptionTable<O> table(
      "ba",
      {
          option("mode", &O::mode, one_of({"proposed", "geva", "naive", "all"}),
                 {"",
                  "`all`, `proposed`, `geva` or `naive`: which BA to run: no surface factors "
                  "(`naive`), every feature on the model, λ = 1 (`geva`, Geva et al.), the binary "
                  "max-mixture with λ from Eq. (7) (`proposed`), or the three in turn. Artifacts "
                  "come from `proposed` when it ran, else the last mode",
                  "seed 001 Sec. 4"}),
          option("tracks", &O::tracks, one_of({"frontend", "ground_truth"}),
                 {"",
                  "`frontend` or `ground_truth`: feature tracks from the SIFT frontend on the "
                  "images, or the simulator's exact tracks listed in truth.yaml "
                  "(`feature_tracks`, docs/mission-format.md)",
                  "frontend: Sec. 2.7; `ground_truth` is for testing"}),
          option("camera_sensor", &O::camera_sensor,
                 {"", "the (rectified, undistorted pinhole) camera; must ride the servo tray", "",
                  "", "`\"\"` = first `camera`"}),
          option("dvl_ranges_sensor", &O::dvl_ranges_sensor,
                 {"", "the 4-beam DVL range sensor of Eq. (14); must ride the servo tray",
                  "Sec. 2.5, 2.6", "", "`\"\"` = first `dvl_ranges`"}),
          option(
              "servo_sensor", &O::servo_sensor,
              {"", "servo angle stream of Eq. (10)", "Sec. 2.6.1", "", "`\"\"` = first `servo`"}),
          option("depth_sensor", &O::depth_sensor,
                 {"", "pressure depth for Eq. (9); must be empty when `use_depth` is false",
                  "Sec. 2.6.1", "", "`\"\"` = first `depth` stream"}),
          option("use_depth", &O::use_depth,
                 {"",
                  "Eq. (9)'s z from the pressure sensor (interpolated at each image); false: no "
                  "depth sensor used. No depth sensor in the mission: none used, silently",
                  "Sec. 2.6.1"}),
          option("dvl_max_dt_s", &O::dvl_max_dt_s, greater_than(0),
                 {"s",
                  "> 0: each keyframe takes the DVL range ping nearest its image if within this; "
                  "else it has no Eq. (14) ranges",
                  "beyond the paper"}),
          option("servo_window_s", &O::servo_window_s, at_least(0),
                 {"s",
                  "≥ 0: servo angle at an image: intercept of a line fitted to the samples within "
                  "±`servo_window_s`/2 of it (falls back to interpolation with fewer than 3 "
                  "samples; 0: interpolation)",
                  "beyond the paper: smooths a noisy servo encoder"}),
          option("triangulation_max_reprojection_px", &O::triangulation_max_reprojection_px,
                 greater_than(0),
                 {"px",
                  "> 0: initial landmarks whose tracks reproject further than this from the "
                  "initial poses are dropped (overrides `ba::TriangulationOptions`' 20 px)",
                  "beyond the paper, which starts from its online SLAM's landmarks: 20 px kept 18 "
                  "of 307 tracks on keel-sim hauv-hull, 80 px kept all"}),
          option(
              "max_keyframes", &O::max_keyframes, int_at_least(0),
              {"", "≥ 0. 0: every image is a keyframe; N: the first N only (short test runs)", ""}),
          option("max_iterations", &O::max_iterations, int_at_least(1),
                 {"", "≥ 1: Ceres iterations per mode", ""}),
          option("function_tolerance", &O::function_tolerance, in_open_range(0, 1),
                 {"",
                  "in (0, 1): Ceres stops a mode's solve when an iteration lowers the cost by less "
                  "than this fraction of it",
                  "Ceres's default. On keel-sim hauv-hull every solve is within 1e-4 of its final "
                  "cost by iteration 6-7 and the last 1-3 iterations gain ~2e-6 each; 1e-5 would "
                  "stop every mode after 8-9 iterations (see the timing section below)"}),
          option("threads", &O::threads, int_at_least(1),
                 {"",
                  "≥ 1: threads of the mesh queries (signed distances to the CAD) and of the "
                  "columns of x_gM's covariance; Ceres solves on one thread whatever this is, so "
                  "the outputs are the same to the bit on any number of threads, run after run",
                  "beyond the paper: on several threads Ceres sums the residual blocks in the "
                  "order its threads take them, and every `ba` output changed at ~1e-11 from run "
                  "to run"}),
          option("linear_solver", &O::linear_solver,
                 one_of({"sparse_schur", "iterative_schur", "dense_schur"}),
                 {"",
                  "`sparse_schur`, `iterative_schur` or `dense_schur`: Ceres linear solver; "
                  "`sparse_schur` (landmarks eliminated, sparse Cholesky on the reduced camera "
                  "system) is the paper's \"sparse Cholesky\"",
                  "Sec. 4.1"}),
          option("dvl_range_normal", &O::dvl_range_normal, one_of({"interpolated", "facet"}),
                 {"",
                  "`interpolated` or `facet`: normal that linearises a DVL beam's range at its "
                  "hit point: the smooth surface's (the hit face's corner normals blended by "
                  "barycentric coordinates; a corner averages the faces round its vertex reached "
                  "across edges of at most 30°, so steeper edges stay creases) or the hit "
                  "facet's. The range itself is the facet range either way, and where the smooth "
                  "plane meets the beam at under half the facet's cosine the facet normal is "
                  "used. On keel-sim hauv-hull (`bench_hull_sim 3 0`, 9 solves) `facet` took 121 "
                  "iterations with 28 rejected steps (beams crossing facet edges, up to 24 "
                  "iterations in one solve), `interpolated` 84 with none, at the same DVL "
                  "residuals and shapes",
                  "Eq. (14)"}),
          option(
              "histogram_bin_m", &O::histogram_bin_m, greater_than(0),
              {"m", "> 0: bin width of the report's histogram of DVL range residuals", "Fig. 18"}),
          option("histogram_range_m", &O::histogram_range_m,
                 {"m",
                  "in [`histogram_bin_m`, 10000 · `histogram_bin_m`]: the histogram covers "
                  "[−range, +range]",
                  "Fig. 18"}),
          option("cad_draco_position_bits", &O::cad_draco_position_bits, int_in_range(1, 30),
                 {"",
                  "in [1, 30]: position quantization of `cad_model.drc` (the job's CAD mesh as "
                  "Draco, model frame): 16 bits keep the error ≤ √3/2 · 30 m / (2¹⁶ − 1) = 0.4 mm "
                  "on a 30 m hull, as `inspect`'s `mesh_remeshed.drc`",
                  ""}),
      },
      [](const O& o, const std::string& path) {
        require(o.use_depth || o.depth_sensor.empty(), path + ".depth_sensor",
                "empty when use_depth is false");
        require(o.histogram_range_m >= o.histogram_bin_m &&
                    o.histogram_range_m / o.histogram_bin_m <= 10000,
                path + ".histogram_range_m",
                "a number in [histogram_bin_m, 10000 * histogram_bin_m]");
      });
  return table;
}

}  // namespace

BaStageOptions BaStageOptions::from_json(const nlohmann::json& options) {
  return table().from_json(options);
}

const OptionsSchema& BaStage::options() const { return table(); }

std::vector<ba::BaMode> BaStageOptions::modes() const {
  if (mode == "all") return {ba::BaMode::kNaive, ba::BaMode::kGeva, ba::BaMode::kProposed};
  return {ba::ba_mode_from_string(mode)};
}

ba::BaOptions BaStageOptions::solver_options() const {
  ba::BaOptions o;
  o.modes = modes();
  o.max_iterations = max_iterations;
  o.function_tolerance = function_tolerance;
  o.num_threads = threads;
  o.linear_solver = linear_solver;
  o.dvl_range_normal =
      dvl_range_normal == "facet" ? ba::DvlRangeNormal::kFacet : ba::DvlRangeNormal::kInterpolated;
  o.triangulation.max_reprojection_px = triangulation_max_reprojection_px;
  return o;
}

}  // namespace keel::pipeline
