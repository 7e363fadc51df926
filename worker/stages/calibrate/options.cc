#include "worker/stages/calibrate/options.h"

#include <cmath>

#include "worker/mapping/map_metrics.h"
#include "worker/stages/calibrate/stage.h"

namespace keel::pipeline {
namespace {

using nlohmann::json;
using Options = CalibrateStageOptions;
using Row = OptionRow<Options>;

OptionDoc doc(const char* unit, std::string meaning, const char* source, const char* group,
              const char* default_text = "") {
  return {unit, std::move(meaning), source, group, default_text};
}

Check<double> positive_metres() {
  return [](const double& v) {
    return std::isfinite(v) && v > 0.0 ? std::string() : "expected a length in metres > 0";
  };
}

// `--set calibrate.candidates=sonar` arrives as a string; `["lidar_v","sonar"]` as an array.
Row candidates_row(OptionDoc doc) {
  Row row{"candidates", "array of strings", std::move(doc), {}, {}};
  row.read = [](Options& o, const json& value, const std::string& path) {
    o.candidates = value.is_string()
                       ? std::vector<std::string>{value.get<std::string>()}
                       : proto::FieldReader::convert<std::vector<std::string>>(value, path);
  };
  row.write = [](const Options& o) { return json(o.candidates); };
  return row;
}

// A count: read as a signed integer so that a negative one is refused, not wrapped.
Row count_row(const char* name, size_t Options::*field, OptionDoc doc) {
  Row row{name, "integer", std::move(doc), {}, {}};
  row.read = [field](Options& o, const json& value, const std::string& path) {
    const auto n = proto::FieldReader::convert<long long>(value, path);
    require(n >= 0, path, "an integer >= 0");
    o.*field = static_cast<size_t>(n);
  };
  row.write = [field](const Options& o) { return json(o.*field); };
  return row;
}

void validate(const Options& o, const std::string& path) {
  require(o.final_correspondence_m <= o.max_correspondence_m, path + ".final_correspondence_m",
          "a gate <= max_correspondence_m (" + number_text(o.max_correspondence_m) + ")");
}

std::string metrics_radius(const double& v) {
  return std::isfinite(v) && v > 0.0 && v <= mapping::kMaxMetricsRadiusM
             ? std::string()
             : "expected a radius in metres in (0, 1] (Table V: 0.25)";
}

const char* const kSensors = "**Sensors and scans** (seed 000 Algorithm 3)";
const char* const kRefinement = "**Refinement** (robust point-to-plane ICP, docs/calibration.md)";
const char* const kMetrics = "**Metrics** (seed 000 Table V, Eqs. (23)-(26))";

}  // namespace

const OptionTable<CalibrateStageOptions>& calibrate_option_table() {
  static const OptionTable<Options> table(
      "calibrate",
      {
          option("reference", &Options::reference,
                 doc("", "the sensor the candidates are calibrated against (S_r)",
                     "seed 000 Algorithm 3", kSensors, "first lidar with scans")),
          candidates_row(doc("",
                             "the sensors to calibrate (S_c). Sensors with `mounted_on` (servo "
                             "trays) are skipped by default: their extrinsic varies",
                             "seed 000 Algorithm 3", kSensors,
                             "every other lidar and sonar with scans")),
          option("keyframe_stride", &Options::keyframe_stride, int_in_range(1, 100000),
                 doc("keyframes", "use every n-th keyframe's scans", "", kSensors)),
          option("scan_voxel_m", &Options::scan_voxel_m, positive_metres(),
                 doc("m",
                     "voxel leaf of every keyframe scan (calibration_scans.bin holds the same "
                     "points, so the browser's window stays small)",
                     "beyond the paper", kSensors)),
          option("max_sweep_duration_s", &Options::max_sweep_duration_s, greater_than(0.0),
                 doc("s", "per-point time spans above this are refused (a unit mistake)", "",
                     kSensors)),
          option("odometry_correction", &Options::odometry_correction,
                 doc("", "correct the recorded `odometry` by the keyframe poses",
                     "seed 000 Algorithm 2", kSensors)),
          option("loss", &Options::loss, one_of({"huber", "cauchy"}),
                 doc("", "robust loss of the point-to-plane residuals", "", kRefinement)),
          option("loss_scale_m", &Options::loss_scale_m, positive_metres(),
                 doc("m", "residuals beyond it are down-weighted", "", kRefinement)),
          option("max_correspondence_m", &Options::max_correspondence_m, positive_metres(),
                 doc("m",
                     "first correspondence gate (distance to the nearest reference point), "
                     "halved every iteration down to final_correspondence_m; also the gate of "
                     "the overlap check",
                     "", kRefinement)),
          option("final_correspondence_m", &Options::final_correspondence_m, positive_metres(),
                 doc("m", "last gate, and the residual histograms' range", "", kRefinement)),
          option("sonar_plane_extrapolation_m", &Options::sonar_plane_extrapolation_m,
                 at_least(0.0),
                 doc("m",
                     "a sonar point farther than the gate from every reference point still "
                     "matches the plane of its nearest reference point within this distance, "
                     "when it lies within the gate of that plane: a sonar sees under the water, "
                     "the reference lidar above it, and they share the planes of piers and walls "
                     "across the waterline, not points. 0 = as a lidar",
                     "beyond the paper", kRefinement)),
          option("max_iterations", &Options::max_iterations, int_in_range(1, 1000),
                 doc("", "ICP iterations (new correspondences each)", "", kRefinement)),
          option("unobservable_ratio", &Options::unobservable_ratio, in_open_range(0.0, 1.0),
                 doc("",
                     "a direction whose information eigenvalue (rotations scaled by the RMS "
                     "range) is below this fraction of the largest is unobservable: reported, "
                     "and the estimate is not moved along it",
                     "Zhang, Kaess, Singh ICRA 2016", kRefinement)),
          count_row("min_overlap_points", &Options::min_overlap_points,
                    doc("points",
                        "a candidate with fewer points near a planar part of the reference map "
                        "is refused",
                        "", kRefinement)),
          option("min_overlap_fraction", &Options::min_overlap_fraction, in_range(0.0, 1.0),
                 doc("", "the same as a fraction of the candidate's points", "", kRefinement)),
          count_row(
              "max_candidate_points", &Options::max_candidate_points,
              doc("points", "candidate points used, evenly strided; 0 = all", "", kRefinement)),
          option("metrics_radius_m", &Options::metrics_radius_m, Check<double>(metrics_radius),
                 doc("m", "r of Eqs. (23)-(26)", "seed 000 Table V", kMetrics)),
          count_row("metrics_max_points", &Options::metrics_max_points,
                    doc("points", "query points of the combined cloud's metrics; 0 = every point",
                        "", kMetrics)),
          option("threads", &Options::threads, int_in_range(1, 256),
                 doc("", "threads of the refinement and the metrics", "", kMetrics)),
      },
      validate);
  return table;
}

mapping::ExtrinsicRefinementOptions CalibrateStageOptions::refinement(
    const std::string& candidate_type) const {
  mapping::ExtrinsicRefinementOptions o;
  if (candidate_type == "sonar") o.plane_extrapolation_m = sonar_plane_extrapolation_m;
  o.loss = loss == "cauchy" ? mapping::RobustLoss::kCauchy : mapping::RobustLoss::kHuber;
  o.loss_scale_m = loss_scale_m;
  o.max_correspondence_m = max_correspondence_m;
  o.final_correspondence_m = final_correspondence_m;
  o.max_iterations = max_iterations;
  o.unobservable_ratio = unobservable_ratio;
  o.min_overlap_points = min_overlap_points;
  o.min_overlap_fraction = min_overlap_fraction;
  o.max_candidate_points = max_candidate_points;
  o.threads = threads;
  o.planes.threads = threads;
  return o;
}

CalibrateStageOptions CalibrateStageOptions::from_json(const json& options) {
  return calibrate_option_table().from_json(options);
}

nlohmann::ordered_json CalibrateStageOptions::to_json() const {
  return calibrate_option_table().to_json(*this);
}

const OptionsSchema& CalibrateStage::options() const { return calibrate_option_table(); }

}  // namespace keel::pipeline
