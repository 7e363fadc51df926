// An ordered list of Table III filters, configurable from JSON (mission options and
// `--set map.filters=...`), applied at one of MapBuilder's three stages (seed 000 Sec. VI-A3):
// each scan (sensor frame), each intermediary map of N_I scans, each sensor's final map.
//
// JSON: an array of objects, e.g.
//   [{"type": "crop_box", "min": [-60,-60,-60], "max": [60,60,60], "remove": "outside"},
//    {"type": "crop_box", "min": [-2,-2,-2], "max": [2,2,2], "remove": "inside"},
//    {"type": "dror", "beta": 3.0, "alpha_deg": 0.2, "k_min": 4, "sr_min": 0.01},
//    {"type": "ror", "radius": 0.1, "min_neighbors": 5},
//    {"type": "voxel_grid", "leaf": 0.05}]
// Omitted numeric keys take the defaults of filters.h; crop_box's min and max are required.
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <variant>
#include <vector>

#include "worker/mapping/filters.h"

namespace keel::mapping {

using FilterSpec = std::variant<CropBoxFilter, VoxelGridFilter, RadiusOutlierFilter, DrorFilter>;

struct FilterChain {
  std::vector<FilterSpec> filters;
  bool empty() const { return filters.empty(); }
  bool has_dror() const;
};

// What one filter did, for the report.
struct FilterStep {
  std::string filter;  // "crop_box", "voxel_grid", "ror", "dror"
  size_t points_in = 0;
  size_t points_out = 0;
};

std::string filter_type(const FilterSpec& filter);
std::vector<FilterStep> apply_filter_chain(const FilterChain& chain, PointCloud& cloud,
                                           int threads = 2);

// Throws std::invalid_argument naming `where`, the index and the field ("map.filters[1].leaf:
// expected a positive number") for anything malformed, including unknown types and keys.
FilterChain filter_chain_from_json(const nlohmann::json& json, const std::string& where);
nlohmann::json filter_chain_to_json(const FilterChain& chain);

// Table IV, seed 000: per-scan filters of the inspection map of Welland Canal Bridge 13.
// Lidar: keep inside +-60 m, remove inside +-2 m (the vessel), DROR {3.0, 0.2, 4, 0.01}.
FilterChain table_iv_lidar_scan_filters();
// Sonar: keep inside +-30 m, remove inside +-2 m, DROR {3.0, 0.5, 4, 0.01}.
FilterChain table_iv_sonar_scan_filters();

}  // namespace keel::mapping
