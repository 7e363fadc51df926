#include "proto/auth.h"

#include "proto/contract_error.h"

namespace keel::proto {

namespace {
constexpr std::pair<Role, const char*> kRoleNames[] = {{Role::kAdmin, "admin"},
                                                       {Role::kSubmitter, "submitter"},
                                                       {Role::kViewer, "viewer"},
                                                       {Role::kWorker, "worker"}};
}  // namespace

std::string to_string(Role role) {
  for (const auto& [value, name] : kRoleNames)
    if (value == role) return name;
  return "unknown";
}

Role role_from_string(std::string_view text, const std::string& path) {
  for (const auto& [value, name] : kRoleNames)
    if (text == name) return value;
  throw ContractError(path + ": unknown role '" + std::string(text) +
                      "' (expected admin, submitter, viewer or worker)");
}

bool is_project_name(std::string_view name) {
  if (name.empty() || name.size() > 64) return false;
  for (size_t i = 0; i < name.size(); ++i) {
    const char c = name[i];
    const bool alnum = (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9');
    if (!alnum && (i == 0 || (c != '.' && c != '_' && c != '-'))) return false;
  }
  return true;
}

void validate_project_name(std::string_view name, const std::string& path) {
  if (!is_project_name(name))
    throw ContractError(path + ": project name '" + std::string(name) +
                        "' must be 1..64 characters of a-z, 0-9, '.', '_' or '-', starting "
                        "with a letter or digit");
}

nlohmann::json TokenInfo::to_json() const {
  return {{"id", id},
          {"label", label},
          {"role", to_string(role)},
          {"project", project},
          {"created_at_ms", created_at_ms},
          {"expires_at_ms", expires_at_ms},
          {"revoked_at_ms", revoked_at_ms}};
}

TokenInfo TokenInfo::from_json(const nlohmann::json& body, const std::string& path) {
  FieldReader r(body, path);
  r.reject_unknown(
      {"id", "label", "role", "project", "created_at_ms", "expires_at_ms", "revoked_at_ms"});
  TokenInfo out;
  out.id = r.required<std::string>("id");
  out.label = r.optional<std::string>("label", "");
  out.role = role_from_string(r.required<std::string>("role"), r.child("role"));
  out.project = r.required<std::string>("project");
  out.created_at_ms = r.optional<int64_t>("created_at_ms", 0);
  out.expires_at_ms = r.optional<int64_t>("expires_at_ms", 0);
  out.revoked_at_ms = r.optional<int64_t>("revoked_at_ms", 0);
  return out;
}

nlohmann::json TokenRequest::to_json() const {
  return {{"label", label},
          {"role", to_string(role)},
          {"project", project},
          {"expires_in_s", expires_in_s}};
}

TokenRequest TokenRequest::from_json(const nlohmann::json& body, const std::string& path) {
  FieldReader r(body, path);
  r.reject_unknown({"label", "role", "project", "expires_in_s"});
  TokenRequest out;
  out.label = r.optional<std::string>("label", "");
  out.role = role_from_string(r.required<std::string>("role"), r.child("role"));
  out.project = r.required<std::string>("project");
  if (out.project == kAllProjects) {
    if (out.role != Role::kAdmin && out.role != Role::kWorker)
      throw ContractError(r.child("project") + ": '*' (every project) is only for admin and "
                                               "worker tokens; a " +
                          to_string(out.role) + " token needs one project");
  } else {
    validate_project_name(out.project, r.child("project"));
  }
  out.expires_in_s = r.optional<int64_t>("expires_in_s", 0);
  if (out.expires_in_s < 0)
    throw ContractError(r.child("expires_in_s") + ": expected seconds >= 0 (0 = never)");
  return out;
}

nlohmann::json Project::to_json() const {
  return {{"name", name},
          {"created_at_ms", created_at_ms},
          {"quota_bytes", quota_bytes},
          {"used_bytes", used_bytes}};
}

Project Project::from_json(const nlohmann::json& body, const std::string& path) {
  FieldReader r(body, path);
  r.reject_unknown({"name", "created_at_ms", "quota_bytes", "used_bytes"});
  Project out;
  out.name = r.required<std::string>("name");
  validate_project_name(out.name, r.child("name"));
  out.created_at_ms = r.optional<int64_t>("created_at_ms", 0);
  out.quota_bytes = r.optional<int64_t>("quota_bytes", 0);
  if (out.quota_bytes < 0) throw ContractError(r.child("quota_bytes") + ": expected bytes >= 0");
  out.used_bytes = r.optional<int64_t>("used_bytes", 0);
  return out;
}

}  // namespace keel::proto
