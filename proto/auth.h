// Who may do what (docs/design.md "Who may do what"): API tokens carry a role and a project.
// Every mission, job, upload, artifact and batch belongs to one project; a token reaches
// only its project's objects (an admin or worker token may hold every project, "*").
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <string_view>

namespace keel::proto {

enum class Role { kAdmin, kSubmitter, kViewer, kWorker };

std::string to_string(Role role);
// Fails with a ContractError naming `path` for an unknown role.
Role role_from_string(std::string_view text, const std::string& path = "role");

// The project of every object made before projects existed, and of a "*" token's objects
// when the request names none.
inline constexpr const char* kDefaultProject = "default";
// A token's project when it reaches every project (admin and worker tokens only).
inline constexpr const char* kAllProjects = "*";

// 1..64 characters of [a-z0-9._-], starting with a letter or digit.
bool is_project_name(std::string_view name);
// Fails with a ContractError naming `path` unless is_project_name(name).
void validate_project_name(std::string_view name, const std::string& path);

// A token as the store keeps it (the clear token itself is never stored).
struct TokenInfo {
  std::string id;            // "t_..."; names the token in lists and revocations
  std::string label;
  Role role = Role::kViewer;
  std::string project;       // a project name, or kAllProjects
  int64_t created_at_ms = 0;
  int64_t expires_at_ms = 0;  // 0 = never
  int64_t revoked_at_ms = 0;  // 0 = not revoked

  bool all_projects() const { return project == kAllProjects; }
  // True when the token may see objects of `object_project`.
  bool reaches(const std::string& object_project) const {
    return all_projects() || project == object_project;
  }

  nlohmann::json to_json() const;
  static TokenInfo from_json(const nlohmann::json& body, const std::string& path = "");
};

// POST /v1/tokens (admin): makes a token; the answer holds the clear token once.
struct TokenRequest {
  std::string label;
  Role role = Role::kViewer;
  std::string project;         // required; kAllProjects only for admin and worker
  int64_t expires_in_s = 0;    // 0 = never

  nlohmann::json to_json() const;
  static TokenRequest from_json(const nlohmann::json& body, const std::string& path = "");
};

// A project and what it holds.
struct Project {
  std::string name;
  int64_t created_at_ms = 0;
  int64_t quota_bytes = 0;  // 0 = no quota
  int64_t used_bytes = 0;   // what it holds now (Store::project_usage); filled by the server

  nlohmann::json to_json() const;
  static Project from_json(const nlohmann::json& body, const std::string& path = "");
};

}  // namespace keel::proto
