#include "worker/stages/map/output_costs.h"

#include "worker/stages/map/map_outputs.h"
#include "worker/stages/map/tiled_maps.h"

namespace keel::pipeline {

double output_budget_bytes(const MapStageOptions& options) {
  return static_cast<double>(options.memory_budget_mb) * (1 << 20) * kOutputShare;
}

double draco_bytes(size_t points, const MapStageOptions& options) {
  const double n = static_cast<double>(points);
  double bytes = (kGatheredBytesPerPoint + kDracoBytesPerPoint) * n;
  if (options.write_point_metrics) bytes += kPointMetricsBytesPerPoint * n;
  if (wants_preview(points, options.preview_max_points))
    bytes += kPreviewBytesPerPoint * static_cast<double>(options.preview_max_points);
  return bytes;
}

double draco_seconds(size_t points, double encode_seconds_per_point,
                     const MapStageOptions& options) {
  const double n = static_cast<double>(points);
  double seconds = encode_seconds_per_point * n;
  if (options.write_point_metrics) seconds += kPointMetricsSecondsPerPoint * n;
  if (wants_preview(points, options.preview_max_points))
    seconds += kDracoSecondsPerPoint * static_cast<double>(options.preview_max_points);
  return seconds;
}

}  // namespace keel::pipeline
