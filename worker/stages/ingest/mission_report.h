// The ingest stage's report of each part of a mission bundle (docs/mission-format.md): its
// sensors' records, its trajectories and its CAD mesh. Each appends what is questionable but
// usable to `warnings` (a JSON array of strings) and throws, naming the file, what is not.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "core/pose.h"
#include "core/time.h"
#include "proto/mission_manifest.h"
#include "worker/io/mission_reader.h"
#include "worker/pipeline/stage.h"
#include "worker/stages/ingest/options.h"

namespace keel::pipeline {

// Count, span, measured rate and, with a nominal rate (> 0), the gaps of a stamp series
// (strictly increasing) named `name` in warnings.
nlohmann::json stamp_report(const std::vector<TimeNs>& stamps, double nominal_rate_hz,
                            const IngestOptions& options, const std::string& name,
                            nlohmann::json& warnings);

// A sensor's records: their stamps (stamp_report) and, per type, invalid DVL samples, missing
// beam returns, points per scan and the span of the per-point time field, image formats; where
// they come from and whose extrinsic applies. `progress` gets the fraction of scans or images
// read.
nlohmann::json sensor_report(const io::MissionReader& reader, const proto::SensorSpec& sensor,
                             const IngestOptions& options, StageContext& context,
                             nlohmann::json& warnings, const std::function<void(double)>& progress);

// A trajectory's poses: their stamps and the path length.
nlohmann::json trajectory_report(const Trajectory& trajectory, const IngestOptions& options,
                                 const std::string& name, nlohmann::json& warnings);

// The CAD mesh's size, area, closedness, degenerate triangles and units check (io::check_mesh).
nlohmann::json cad_report(const std::filesystem::path& path, nlohmann::json& warnings);

}  // namespace keel::pipeline
