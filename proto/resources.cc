#include "proto/resources.h"

#include "proto/auth.h"
#include "proto/contract_error.h"

namespace keel::proto {

bool is_sha256_hex(const std::string& text) {
  if (text.size() != 64) return false;
  for (char c : text)
    if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) return false;
  return true;
}

static std::string required_sha(const FieldReader& r, const char* field) {
  std::string value = r.required<std::string>(field);
  if (!is_sha256_hex(value))
    throw ContractError(r.child(field) + ": expected 64 lowercase hex digits (SHA-256)");
  return value;
}

static std::string optional_project(const FieldReader& r) {
  std::string project = r.optional<std::string>("project", "");
  if (!project.empty()) validate_project_name(project, r.child("project"));
  return project;
}

static std::string optional_sha(const FieldReader& r, const char* field) {
  std::string value = r.optional<std::string>(field, "");
  if (!value.empty() && !is_sha256_hex(value))
    throw ContractError(r.child(field) + ": expected 64 lowercase hex digits (SHA-256)");
  return value;
}

nlohmann::json Upload::to_json() const {
  return {{"id", id},         {"name", name}, {"size", size},
          {"offset", offset}, {"blob", blob}, {"project", project}};
}

Upload Upload::from_json(const nlohmann::json& body, const std::string& path) {
  FieldReader r(body, path);
  r.reject_unknown({"id", "name", "size", "offset", "blob", "project"});
  return {r.required<std::string>("id"),   r.optional<std::string>("name", ""),
          r.required<int64_t>("size"),     r.required<int64_t>("offset"),
          optional_sha(r, "blob"),         r.optional<std::string>("project", "")};
}

nlohmann::json UploadRequest::to_json() const {
  nlohmann::json out = {{"name", name}, {"size", size}};
  if (!project.empty()) out["project"] = project;
  return out;
}

UploadRequest UploadRequest::from_json(const nlohmann::json& body, const std::string& path) {
  FieldReader r(body, path);
  r.reject_unknown({"name", "size", "project"});
  UploadRequest out{r.optional<std::string>("name", ""), r.required<int64_t>("size"),
                    optional_project(r)};
  if (out.size < 0) throw ContractError(r.child("size") + ": expected a size >= 0");
  return out;
}

nlohmann::json Mission::to_json() const {
  return {{"id", id},         {"name", name},         {"bundle_blob", bundle_blob},
          {"cad_blob", cad_blob}, {"cad_name", cad_name}, {"created_at_ms", created_at_ms},
          {"project", project}};
}

Mission Mission::from_json(const nlohmann::json& body, const std::string& path) {
  FieldReader r(body, path);
  r.reject_unknown(
      {"id", "name", "bundle_blob", "cad_blob", "cad_name", "created_at_ms", "project"});
  return {r.required<std::string>("id"),           r.required<std::string>("name"),
          required_sha(r, "bundle_blob"),          optional_sha(r, "cad_blob"),
          r.optional<std::string>("cad_name", ""), r.optional<int64_t>("created_at_ms", 0),
          r.optional<std::string>("project", "")};
}

nlohmann::json MissionRequest::to_json() const {
  nlohmann::json out = {
      {"name", name}, {"bundle_blob", bundle_blob}, {"cad_blob", cad_blob}, {"cad_name", cad_name}};
  if (!project.empty()) out["project"] = project;
  return out;
}

MissionRequest MissionRequest::from_json(const nlohmann::json& body, const std::string& path) {
  FieldReader r(body, path);
  r.reject_unknown({"name", "bundle_blob", "cad_blob", "cad_name", "project"});
  MissionRequest out{r.required<std::string>("name"), required_sha(r, "bundle_blob"),
                     optional_sha(r, "cad_blob"), r.optional<std::string>("cad_name", ""),
                     optional_project(r)};
  if (out.name.empty()) throw ContractError(r.child("name") + ": expected a non-empty name");
  if (!out.cad_blob.empty() && out.cad_name.empty())
    throw ContractError(r.child("cad_name") + ": required with cad_blob (its extension names the format)");
  return out;
}

nlohmann::json Artifact::to_json() const {
  return {{"id", id},         {"job_id", job_id}, {"stage", stage},
          {"name", name},     {"sha256", sha256}, {"size", size},
          {"created_at_ms", created_at_ms}, {"project", project}};
}

Artifact Artifact::from_json(const nlohmann::json& body, const std::string& path) {
  FieldReader r(body, path);
  r.reject_unknown(
      {"id", "job_id", "stage", "name", "sha256", "size", "created_at_ms", "project"});
  return {r.required<std::string>("id"),    r.required<std::string>("job_id"),
          r.required<std::string>("stage"), r.required<std::string>("name"),
          required_sha(r, "sha256"),        r.required<int64_t>("size"),
          r.optional<int64_t>("created_at_ms", 0), r.optional<std::string>("project", "")};
}

}  // namespace keel::proto
