// What a Draco file holds, read from the decoded file itself: point and face counts, the box of
// the decoded positions, and each generic attribute's unique id (what three.js's DRACOLoader
// looks attributes up by), metadata name, range of the stored values (after quantization) and,
// for a label attribute, its labels. The pipeline writes it as a map's or mesh's sidecar JSON.
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace keel::io {

// Metadata entry of a label attribute (such as a combined map's `sensor`): the labels as a JSON
// array of strings, label k for stored value k.
inline constexpr const char* kDracoLabelsEntry = "labels";
// Metadata entry of a field with a value meaning "undefined" (PartsAttributes::fields_no_data).
inline constexpr const char* kDracoNoDataEntry = "no_data";

struct DracoAttributeSummary {
  std::string name;  // metadata entry "name" ("generic_<id>" when it has none)
  int unique_id = 0;
  std::string data_type;  // "float32", "uint8", ...
  int components = 1;
  // Over every component of every point's stored value, leaving out no_data; both NaN when no
  // value is left.
  double min = 0.0, max = 0.0;
  std::vector<std::string> labels;  // from metadata entry "labels"; empty for other attributes
  std::optional<double> no_data;    // from metadata entry "no_data"
};

struct DracoSummary {
  std::string kind;  // "point_cloud" | "mesh"
  size_t points = 0;
  size_t faces = 0;
  Eigen::Vector3d bbox_min = Eigen::Vector3d::Zero(), bbox_max = Eigen::Vector3d::Zero();
  int position_unique_id = -1;                    // the POSITION attribute's (-1: none)
  std::vector<DracoAttributeSummary> attributes;  // generic attributes, in file order
};

// Decodes `bytes`; throws std::runtime_error naming `what` when they are not a Draco geometry.
DracoSummary summarize_draco(const std::string& bytes, const std::string& what = "draco buffer");

}  // namespace keel::io
