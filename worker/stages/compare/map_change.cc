#include "worker/stages/compare/compare_maps.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "worker/mapping/map_metrics.h"

namespace keel::pipeline {
namespace {

using nlohmann::json;

// Histogram of the defined changes over [-range, range] with under- and overflow counts.
json change_histogram(const std::vector<compare::CoreChange>& cores, int bins, double range) {
  std::vector<double> area(bins, 0.0);
  std::vector<size_t> count(bins, 0);
  size_t below = 0, above = 0;
  for (const auto& c : cores) {
    if (!c.defined()) continue;
    if (c.distance_m < -range) {
      ++below;
      continue;
    }
    if (c.distance_m >= range) {
      ++above;
      continue;
    }
    const int bin = std::min(bins - 1, int((c.distance_m + range) / (2.0 * range) * bins));
    ++count[bin];
    area[bin] += c.area_m2;
  }
  std::vector<double> edges(bins + 1);
  for (int i = 0; i <= bins; ++i) edges[i] = -range + 2.0 * range * i / bins;
  return {{"edges_m", edges},
          {"core_points", count},
          {"area_m2", area},
          {"below", below},
          {"above", above}};
}

// A value just below the smallest defined one (by 1/1024 of the range, as the map stage's
// per-point metrics): what a point holds where its core point's change is undefined.
float no_data_below(const std::vector<compare::CoreChange>& cores,
                    float compare::CoreChange::*field) {
  float lo = std::numeric_limits<float>::infinity(), hi = -lo;
  for (const auto& c : cores)
    if (c.defined()) lo = std::min(lo, c.*field), hi = std::max(hi, c.*field);
  if (!(lo <= hi)) lo = hi = 0.0f;
  const float span = std::max(hi - lo, std::max(std::fabs(lo), 1.0f) * 1e-6f);
  return lo - span / 1024.0f;
}

}  // namespace

ChangeCloud change_cloud(const std::vector<compare::CoreChange>& changes,
                         const std::vector<uint32_t>& core_of, const std::vector<float>& c2c,
                         std::vector<Eigen::Vector3f> points) {
  const float m3c2_no_data = no_data_below(changes, &compare::CoreChange::distance_m);
  const float lod_no_data = no_data_below(changes, &compare::CoreChange::lod95_m);
  std::vector<float> m3c2(points.size()), lod(points.size()), significant(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    const compare::CoreChange& c = changes[core_of[i]];
    m3c2[i] = c.defined() ? c.distance_m : m3c2_no_data;
    lod[i] = c.defined() ? c.lod95_m : lod_no_data;
    significant[i] = c.defined() ? (c.significant ? 1.0f : 0.0f) : -1.0f;
  }
  ChangeCloud out;
  out.cloud.xyz = std::move(points);
  out.cloud.frame = "world";
  out.attributes.fields = {{"m3c2_m", std::move(m3c2)},
                           {"lod95_m", std::move(lod)},
                           {"significant", std::move(significant)},
                           {"c2c_m", c2c}};
  out.attributes.fields_no_data = {m3c2_no_data, lod_no_data, std::nanf(""), std::nanf("")};
  return out;
}

json change_figures(const std::vector<compare::CoreChange>& changes, const std::vector<float>& c2c,
                    const CompareStageOptions& options) {
  double defined_area = 0, significant_area = 0, added = 0, removed = 0;
  size_t defined = 0, significant_cores = 0;
  std::vector<float> distances, lods;
  for (const auto& c : changes) {
    if (!c.defined()) continue;
    ++defined;
    defined_area += c.area_m2;
    distances.push_back(c.distance_m);
    lods.push_back(c.lod95_m);
    if (!c.significant) continue;
    ++significant_cores;
    significant_area += c.area_m2;
    (c.distance_m > 0 ? added : removed) += c.area_m2;
  }
  json r;
  r["core_points"] = changes.size();
  r["defined_core_points"] = defined;
  r["significant_core_points"] = significant_cores;
  r["compared_area_m2"] = defined_area;
  r["significant_area_m2"] = significant_area;
  r["significant_fraction"] = defined_area > 0 ? significant_area / defined_area : 0.0;
  r["significant_added_area_m2"] = added;  // change > 0: material towards the sensor
  r["significant_removed_area_m2"] = removed;
  r["m3c2_m"] = mapping::to_json(mapping::summarize(distances, options.histogram_bins));
  r["lod95_m"] = mapping::to_json(mapping::summarize(lods, options.histogram_bins));
  r["c2c_m"] = mapping::to_json(mapping::summarize(c2c, options.histogram_bins));
  r["change_histogram"] =
      change_histogram(changes, options.histogram_bins, options.histogram_range_m);
  return r;
}

json level_of_detection(const std::vector<compare::CoreChange>& changes,
                        const std::vector<char>& stable,
                        const std::vector<double>& registration_error_m,
                        const std::vector<compare::TileError>& tiles,
                        const CompareStageOptions& options) {
  size_t on_stable = 0, exceeding = 0;
  for (size_t i = 0; i < stable.size() && i < changes.size(); ++i) {
    if (!stable[i] || !changes[i].defined()) continue;
    ++on_stable;
    exceeding += std::abs(changes[i].distance_m) > changes[i].lod95_m;
  }
  std::vector<float> reg;
  for (size_t i = 0; i < registration_error_m.size() && i < changes.size(); ++i)
    if (changes[i].defined()) reg.push_back(float(registration_error_m[i]));
  json per_tile = json::array();
  for (const compare::TileError& t : tiles)
    per_tile.push_back({{"tile", t.key},
                        {"cores", t.cores},
                        {"stable_cores", t.stable},
                        {"registration_error_m", t.registration_error_m}});
  json r;
  r["confidence_z"] = options.m3c2.confidence_z;
  r["stable_core_points"] = on_stable;
  // Null without a per-tile analysis (registration_error_m given).
  r["exceedance_on_stable"] =
      on_stable ? json(double(exceeding) / double(on_stable)) : json(nullptr);
  r["registration_error_m"] = mapping::to_json(mapping::summarize(reg, options.histogram_bins));
  r["tile_m"] = options.local_registration_tile_m;
  r["per_tile"] = per_tile;
  return r;
}

}  // namespace keel::pipeline
