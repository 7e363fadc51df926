// What the map stage's output tasks are estimated to cost: CPU seconds, which order them
// (costliest first), and peak bytes, which bound the tasks that run side by side within the
// memory budget's output share (OutputRunner). Per map point, measured on the keel-sim bridge
// (14.4 M points in the combined map; the times again on the 220 s bridge, 10.7 M, from the
// job log's task lines).
#pragma once

#include <cstddef>

#include "worker/stages/map/options.h"

namespace keel::pipeline {

// A map gathered in memory for its Draco file (positions and intensity).
inline constexpr double kGatheredBytesPerPoint = 16.0;
// A sensor's Draco file (gathering its tiles, the encoding, the round trip and the preview):
// at its peak Draco's copy of the input, its quantized attributes and the kd-tree's copy of
// them, the output.
inline constexpr double kDracoSecondsPerPoint = 0.5e-6;
inline constexpr double kDracoBytesPerPoint = 48.0;
// The combined map's Draco file in two tasks: the encoding (gathering, encoding, preview; the
// same peak), then the round trip (the decoder's quantized and float copies, and the file).
// The round trip can only start once the encoding ends, so it must not be estimated cheaper
// than it is, or it waits behind shorter tasks at the end of the stage.
inline constexpr double kDracoEncodeSecondsPerPoint = 0.35e-6;
inline constexpr double kDracoCheckSecondsPerPoint = 0.22e-6;
inline constexpr double kDracoCheckBytesPerPoint = 35.0;
// The metrics of Table V (metrics_max_points query points): the cell grid.
inline constexpr double kMetricsSecondsPerPoint = 0.15e-6;
inline constexpr double kMetricsBytesPerPoint = 29.0;
// A PLY file: mostly the kernel's copy, through a buffer of fixed size.
inline constexpr double kPlySecondsPerPoint = 0.05e-6;
// LOD tiles: the octree's splits and thinning, the .pnts encoding.
inline constexpr double kLodSecondsPerPoint = 0.15e-6;
// Per-point metrics of a whole map (every point a query point, ~1600 neighbours each within
// 0.25 m on a 2 cm map): the cell grid and 12 bytes of fields.
inline constexpr double kPointMetricsSecondsPerPoint = 4e-6;
inline constexpr double kPointMetricsBytesPerPoint = kMetricsBytesPerPoint + 12.0;
// A preview's thinned copy (~20 bytes per point) and its encoding.
inline constexpr double kPreviewBytesPerPoint = kDracoBytesPerPoint + 20.0;

// Bytes the output tasks may hold at once: the budget's output share (tiled_maps.h).
double output_budget_bytes(const MapStageOptions& options);

// Peak bytes of a Draco file of a map of `points` points made in memory (the map gathered,
// then encoded), with what the same task makes from the gathered map: the per-point metrics
// (write_point_metrics) and a large map's preview.
double draco_bytes(size_t points, const MapStageOptions& options);
// Seconds of the same, the encoding at `encode_seconds_per_point`.
double draco_seconds(size_t points, double encode_seconds_per_point,
                     const MapStageOptions& options);

}  // namespace keel::pipeline
