#include "worker/stages/compare/options.h"

#include <cmath>

namespace keel::pipeline {
namespace {

using nlohmann::json;
using Options = CompareStageOptions;
using Row = OptionRow<Options>;

// A row for a member of one of the algorithms' option structs held in Options.
template <typename Part, typename T>
Row part_option(const char* name, Part Options::*part, T Part::*field, Check<T> check,
                OptionDoc doc) {
  const OptionRow<Part> inner = option(name, field, std::move(check), std::move(doc));
  Row row{inner.name, inner.type, inner.doc, {}, {}};
  row.read = [inner, part](Options& o, const json& value, const std::string& path) {
    inner.read(o.*part, value, path);
  };
  row.write = [inner, part](const Options& o) { return inner.write(o.*part); };
  return row;
}

// A finite number that `ok` accepts, else "expected <words>".
Check<double> finite(bool (*ok)(double), const char* words) {
  return [ok, words](const double& v) {
    return std::isfinite(v) && ok(v) ? std::string() : std::string("expected ") + words;
  };
}
Check<double> positive() {
  return finite([](double v) { return v > 0; }, "> 0");
}

// Non-empty strings; a failed check says "expected a list of map names" whatever went wrong.
Row sensors_row(OptionDoc words) {
  Row row{"sensors", "array of strings", std::move(words), {}, {}};
  row.read = [](Options& o, const json& value, const std::string& path) {
    bool ok = value.is_array();
    for (size_t i = 0; ok && i < value.size(); ++i)
      ok = value[i].is_string() && !value[i].get<std::string>().empty();
    require(ok, path, "a list of map names");
    o.sensors = value.get<std::vector<std::string>>();
  };
  row.write = [](const Options& o) { return json(o.sensors); };
  return row;
}

// A row's words in docs/stage-options.md (one table: no groups).
OptionDoc doc(std::string unit, std::string meaning, std::string source = "") {
  return {std::move(unit), std::move(meaning), std::move(source), "", ""};
}

}  // namespace

const OptionTable<CompareStageOptions>& compare_option_table() {
  using compare::M3c2Options;
  using compare::StableRegistrationOptions;
  static const OptionTable<Options> table(
      "compare",
      {
          option("job_a", &Options::job_a,
                 doc("",
                     "job A's id, set by the server on a compare job (POST /v1/comparisons); "
                     "a reprocess with \"compare\": true sets it alone, B being the job itself")),
          option("job_b", &Options::job_b,
                 doc("", "job B's id, set by the server on a compare job")),
          sensors_row(doc("",
                          "maps compared; empty: `combined` when both jobs have it, else every "
                          "map both have")),
          option("register", &Options::register_maps,
                 doc("",
                     "register B's maps onto A's first (point-to-plane ICP on stable structure: "
                     "pairs within 3 × 1.4826 MAD of the residuals, at least 5 mm)",
                     "Chen & Medioni 1992; the stable band is ours")),
          part_option("registration_sample_spacing_m", &Options::registration,
                      &StableRegistrationOptions::sample_spacing_m, positive(),
                      doc("m", "> 0. B is sampled at the centroids of voxels of this side")),
          part_option("registration_plane_radius_m", &Options::registration,
                      &StableRegistrationOptions::plane_radius_m, positive(),
                      doc("m", "> 0. A's local planes: least squares within this radius")),
          part_option("registration_max_correspondence_m", &Options::registration,
                      &StableRegistrationOptions::max_correspondence_m, positive(),
                      doc("m", "> 0. Pairs farther apart are never used")),
          part_option("registration_stable_sigmas", &Options::registration,
                      &StableRegistrationOptions::stable_sigmas, positive(),
                      doc("", "> 0. k of the stable band")),
          part_option("registration_max_iterations", &Options::registration,
                      &StableRegistrationOptions::max_iterations, int_in_range(1, 1000),
                      doc("", "in [1, 1000]")),
          option("local_registration_tile_m", &Options::local_registration_tile_m,
                 finite([](double v) { return v >= 0; }, "a number >= 0 (0: off)"),
                 doc("m",
                     "≥ 0. After the global registration, each cubic tile of B of this side gets "
                     "its own rigid correction, estimated from the M3C2 change at B's core "
                     "points every 0.25 m on the structure stable in both surveys (cores beyond "
                     "3 noises, at least 1 cm, and those within 0.5 m of them left out; Huber "
                     "loss), applied only along the directions that structure constrains "
                     "(eigenvalues of its normal matrix), and only when it leaves at least half "
                     "the tile's cores stable and stays within 10 cm / 0.5°: two surveys' maps "
                     "each carry their own trajectory's few-cm errors, which one rigid "
                     "transform cannot remove, and a change must not pull its tile. The tiles "
                     "also give `registration_error_m`. 0: off",
                     "ours")),
          part_option("normal_scale_m", &Options::m3c2, &M3c2Options::normal_scale_m, positive(),
                      doc("m",
                          "> 0. D: diameter of the neighbourhood of A whose plane gives the "
                          "normal at a core point",
                          "Lague et al.: D ≥ 20-25 × roughness")),
          part_option("projection_scale_m", &Options::m3c2, &M3c2Options::projection_scale_m,
                      positive(),
                      doc("m", "> 0. d: diameter of the projection cylinder",
                          "Lague et al.: ≥ ~30 points per cloud in it")),
          part_option("max_depth_m", &Options::m3c2, &M3c2Options::max_depth_m, positive(),
                      doc("m", "> 0. Half-length of the cylinder: the largest change measured")),
          part_option("core_spacing_m", &Options::m3c2, &M3c2Options::core_spacing_m, positive(),
                      doc("m",
                          "> 0. One core point per voxel of B of this side (its centroid); "
                          "every point of B takes its voxel's change")),
          part_option("min_points", &Options::m3c2, &M3c2Options::min_points, int_at_least(2),
                      doc("",
                          "≥ 2. Fewer points of a cloud in a cylinder: the change is undefined "
                          "(`significant` = -1)")),
          part_option(
              "confidence_z", &Options::m3c2, &M3c2Options::confidence_z, positive(),
              doc("", "> 0. The z of the level of detection, Eq. (1) (95 %)", "Lague et al.")),
          option("registration_error_m", &Options::registration_error_m,
                 finite([](double) { return true; }, "a number (< 0: from the registration)"),
                 doc("m",
                     "reg of Eq. (1). < 0: per tile of `local_registration_tile_m` (the whole "
                     "map when 0), the smallest reg with which |M3C2| ≤ LoD95 at 95 % of the "
                     "tile's stable core points (changed cores, and cores within 0.5 m of them, "
                     "left out); ≥ 0: this value everywhere",
                     "Lague et al. take the ICP's RMS; calibrated here, since correlated noise "
                     "and registration error make that miss its 95 %")),
          option("significance_radius_m", &Options::significance_radius_m,
                 finite([](double v) { return v >= 0 && v <= 10; }, "a length in [0, 10] m"),
                 doc("m",
                     "in [0, 10]. A core point's change is significant when |M3C2| > LoD95 there "
                     "and, with its sign, at at least half the core points within this radius: "
                     "the 5 % of unchanged cores beyond a 95 % level are scattered, a change "
                     "covers a patch. 0: beyond LoD95 alone")),
          option("significance_z", &Options::significance_z, positive(),
                 doc("",
                     "> 0. A core's change is significant when |M3C2| > z (statistical + reg) "
                     "with reg calibrated at this confidence (2.576: 99 %), not at LoD95's: the "
                     "95 % level leaves 5 % of unchanged structure beyond it by its definition")),
          option("histogram_bins", &Options::histogram_bins, int_in_range(1, 1000),
                 doc("", "in [1, 1000]. Bins of the change histogram")),
          option("histogram_range_m", &Options::histogram_range_m, positive(),
                 doc("m", "> 0. The change histogram spans ±this")),
          option("draco_position_bits", &Options::draco_position_bits, int_in_range(1, 30),
                 doc("",
                     "in [1, 30]. Position quantization of `change_<map>.drc` (hull: at most "
                     "16)")),
          option("draco_field_bits", &Options::draco_field_bits, int_in_range(0, 30),
                 doc("", "in [0, 30]. Quantization of the change files' attributes")),
          option("draco_compression_level", &Options::draco_compression_level, int_in_range(0, 10),
                 doc("",
                     "in [0, 10]. Draco's compression level of the change files (speed = 10 - "
                     "level), as the map stage's: on the 220 s bridge's change map the "
                     "single-threaded encode, the stage's critical path, takes 5.4 CPU s at 5 "
                     "against 12.6 s at 7, for a file 38 % larger (63.9 vs 46.2 MB); the values "
                     "decode the same")),
          option("write_ply", &Options::write_ply,
                 doc("", "also write `change_<map>.ply` / `change_hull.ply`")),
          option("growth_sigmas", &Options::growth_sigmas, positive(),
                 doc("",
                     "> 0. A kept hull shape grew significantly when |height growth| > this "
                     "× its sigma (in quadrature: the two jobs' "
                     "`inspect.deviation_noise_sigma_m` and both shapes' "
                     "`height_sampling_sigma_m`, how far each top may lie beyond its highest "
                     "feature; see the `inspect` section)")),
          option("shape_max_offset_m", &Options::shape_max_offset_m,
                 finite([](double v) { return v >= 0 && v <= 10; }, "a length in [0, 10] m"),
                 doc("m",
                     "in [0, 10]. The largest frame offset between the two surveys' shapes "
                     "that matching corrects: each survey's x_gM is loose along a prismatic "
                     "hull (keel-sim: 0.2-0.5 m off along it), so A's shapes are first moved "
                     "by the offset most persisting shapes agree on (at least two; "
                     "changes.json `shape_registration`); 0 = match where each x_gM put them")),
          option("threads", &Options::threads, int_in_range(1, 256),
                 doc("",
                     "in [1, 256]. Threads of every step: the two decodes and the indexes side "
                     "by side, the local registration's tiles, C2C and M3C2 split over the "
                     "points; the Draco encoding of `change_<map>.drc` is single-threaded, the "
                     "PLY file and the figures are made beside it")),
      });
  return table;
}

}  // namespace keel::pipeline
