// Uploads, missions and artifacts as the API shows them.
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>

namespace keel::proto {

// A resumable upload: bytes [0, offset) are committed; completing it with the right
// SHA-256 turns it into a content-addressed blob.
struct Upload {
  std::string id;
  std::string name;    // the client's file name, for logs
  int64_t size = 0;    // total bytes announced at creation
  int64_t offset = 0;  // bytes committed so far
  std::string blob;    // SHA-256 hex once completed, else ""
  std::string project;

  nlohmann::json to_json() const;
  static Upload from_json(const nlohmann::json& body, const std::string& path = "");
};

// POST /v1/uploads body.
struct UploadRequest {
  std::string name;
  int64_t size = 0;
  std::string project;  // optional in JSON; the server checks it against the token's project

  nlohmann::json to_json() const;
  static UploadRequest from_json(const nlohmann::json& body, const std::string& path = "");
};

// A stored mission: a bundle blob (a tar of the mission folder) and an optional CAD mesh blob.
struct Mission {
  std::string id;
  std::string name;
  std::string bundle_blob;  // SHA-256 hex of the bundle tar
  std::string cad_blob;     // SHA-256 hex of the CAD mesh, "" when none
  std::string cad_name;     // file name of the CAD mesh (its extension tells the format)
  int64_t created_at_ms = 0;
  std::string project;

  nlohmann::json to_json() const;
  static Mission from_json(const nlohmann::json& body, const std::string& path = "");
};

// POST /v1/missions body.
struct MissionRequest {
  std::string name;
  std::string bundle_blob;
  std::string cad_blob;
  std::string cad_name;
  std::string project;  // optional in JSON; the server checks it against the token's project

  nlohmann::json to_json() const;
  static MissionRequest from_json(const nlohmann::json& body, const std::string& path = "");
};

// A job's output file, content-addressed.
struct Artifact {
  std::string id;
  std::string job_id;
  std::string stage;   // the stage that produced it
  std::string name;    // e.g. "map_combined.drc", "report.json"
  std::string sha256;  // blob id
  int64_t size = 0;
  int64_t created_at_ms = 0;
  std::string project;  // the job's project

  nlohmann::json to_json() const;
  static Artifact from_json(const nlohmann::json& body, const std::string& path = "");
};

// True for 64 lowercase hex digits.
bool is_sha256_hex(const std::string& text);

}  // namespace keel::proto
