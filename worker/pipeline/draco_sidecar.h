// The sidecar of a Draco artifact (docs/artifacts.md, "Draco sidecar"): `<name>.json` beside
// `<name>.drc`, telling a viewer the counts, the box and each attribute's unique id and value
// range (and labels) without decoding the file, and the preview to open first when there is one.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>

#include "worker/io/draco/draco_summary.h"

namespace keel::pipeline {

// "map_combined.drc" -> "map_combined.json".
std::string sidecar_file(const std::string& draco_file);

// The sidecar document (pure). `frame`: "world" or "model" (docs/artifacts.md, "Frames");
// `preview`: {"file", "points"} of the file's preview, or null.
nlohmann::ordered_json draco_sidecar_json(const std::string& draco_file,
                                          const io::DracoSummary& summary, const std::string& frame,
                                          const nlohmann::json& preview = nullptr);

// Writes sidecar_file(draco_file) into work_dir (atomically); returns its name.
std::string write_draco_sidecar(const std::filesystem::path& work_dir,
                                const std::string& draco_file, const io::DracoSummary& summary,
                                const std::string& frame, const nlohmann::json& preview = nullptr);

}  // namespace keel::pipeline
