// `keel submit`: bundle a mission folder, upload it (and a CAD mesh) resumably, create the
// mission and the job. Re-running an interrupted submit resumes the uploads where the
// server's committed offsets are and gets the same job back (Idempotency-Key).
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

#include "client/api_client.h"
#include "proto/job.h"
#include "proto/resources.h"

namespace keel::client {

struct SubmitOptions {
  std::filesystem::path mission_dir;
  std::filesystem::path cad_file;  // empty = none
  std::vector<std::string> stages;
  nlohmann::json options = nlohmann::json::object();
  std::string name;  // empty = mission.yaml's `name:`, else the folder's name
  std::filesystem::path cache_dir;
  bool show_progress = true;
};

struct SubmitResult {
  std::string bundle_blob;
  std::string cad_blob;
  proto::Mission mission;
  proto::Job job;
};

// SHA-256 of {"bundle","cad","stages","options"} as compact JSON with sorted keys: the same
// inputs give the same key, so the server answers a repeated POST /v1/jobs with the job
// it made the first time.
std::string submit_idempotency_key(const std::string& bundle_blob, const std::string& cad_blob,
                                   const std::vector<std::string>& stages,
                                   const nlohmann::json& options);

// mission.yaml's `name:` when it has one, else the folder's name. Throws LocalFileError
// when the folder or its mission.yaml is missing.
std::string mission_name_of(const std::filesystem::path& mission_dir);

SubmitResult submit_mission(ApiClient& api, const SubmitOptions& options);

}  // namespace keel::client
