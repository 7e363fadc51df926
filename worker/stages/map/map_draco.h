// A map's single Draco file, map_<name>.drc with its sidecar (docs/artifacts.md), and the
// error check the report gives with it: the round trip that decodes the file and measures
// the largest position error against the map. The file is made in memory from the map's
// tiles, so only when that fits the budget's output share (output_costs.h). A sensor map is
// encoded and checked in one task; the combined map (Eq. (21)), the largest, in two that run
// on different threads, the encoding and then the check.
#pragma once

#include <chrono>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "worker/io/draco/draco_codec.h"
#include "worker/stages/map/map_outputs.h"
#include "worker/stages/map/options.h"
#include "worker/stages/map/tiled_maps.h"

namespace keel::pipeline {

io::DracoOptions draco_options(const MapStageOptions& options);

// The report of a map whose Draco file would need `needed_bytes`, over `budget_bytes`.
MapOutput draco_not_written(size_t points, double needed_bytes, double budget_bytes);

// Writes map_<name>.drc of the sensor map `name` (`points` points) into `draco`, then its
// preview, when the map is larger than preview_max_points, into `preview`; each is filled
// as soon as its file is written, so a failure leaves the files written so far listed.
void write_sensor_draco(TiledMaps& tiled, const std::string& name, size_t points,
                        const MapStageOptions& options, const std::filesystem::path& work_dir,
                        const std::function<void()>& check_canceled, MapOutput& draco,
                        MapOutput& preview);

// The combined map's Draco file, each point labelled with its sensor (kSensorAttribute).
class CombinedDraco {
 public:
  // `parts`: the sensor maps of TiledMaps that make the combined map, in order.
  CombinedDraco(TiledMaps& tiled, std::vector<std::string> parts, size_t points,
                const MapStageOptions& options, std::filesystem::path work_dir);
  // The first task: gathers the parts from their tiles and encodes them, writing the preview
  // (when wanted) into `preview`.
  void encode(const std::function<void()>& check_canceled, MapOutput& preview);
  // The second: the round trip of the encoding, then map_combined.drc into `draco`; frees the
  // gathered maps.
  void check(MapOutput& draco);

 private:
  std::vector<const PointCloud*> part_pointers() const;

  TiledMaps& tiled_;
  const MapStageOptions& options_;
  const std::filesystem::path work_dir_;
  const size_t points_;
  std::vector<std::string> parts_;
  io::PartsAttributes attributes_;  // each point's sensor, and per-point metrics when written
  std::vector<PointCloud> maps_;    // the parts, gathered
  io::DracoEncoded encoded_;
  double encode_seconds_ = 0.0;
};

}  // namespace keel::pipeline
