// Token and project administration: POST/GET /v1/tokens, POST /v1/tokens/{id}/revoke (admin),
// GET /v1/projects[/{name}] (what a token reaches, with usage) and PUT /v1/projects/{name}
// (quotas; an admin of every project).
//
// An admin token of one project manages that project's tokens only: another project's token
// answers 404 as an unknown id, and it cannot make "*" tokens.
#include "proto/auth.h"
#include "proto/contract_error.h"
#include "server/api_response.h"
#include "server/routes.h"
#include "server/token_admin.h"

namespace keel::server::routes {

namespace {

int64_t now_ms(const Call& call) {
  return call.options.wall_clock_ms ? call.options.wall_clock_ms() : storage::system_clock_ms();
}

proto::TokenInfo reachable_token(const Call& call, const std::string& token_id) {
  for (const proto::TokenInfo& token : call.store.list_tokens())
    if (token.id == token_id &&
        (call.principal.all_projects() || token.project == call.principal.project))
      return token;
  throw ApiException(404, "not_found", "token " + token_id + " not found");
}

proto::Project with_usage(const Call& call, proto::Project project) {
  project.used_bytes = call.store.project_usage(project.name);
  return project;
}

}  // namespace

Response create_token(const Call& call) {
  const proto::TokenRequest request = proto::TokenRequest::from_json(parse_json_body(call.request));
  if (!call.principal.all_projects() && request.project != call.principal.project)
    throw ApiException(404, "not_found",
                       "project " + request.project +
                           " not found (an admin of one project makes tokens of that project)");
  const IssuedToken issued = issue_token(call.store, request, now_ms(call));
  return json_response(201, {{"token", issued.token}, {"info", issued.info.to_json()}});
}

Response list_tokens(const Call& call) {
  nlohmann::json tokens = nlohmann::json::array();
  for (const proto::TokenInfo& token : call.store.list_tokens())
    if (call.principal.all_projects() || token.project == call.principal.project)
      tokens.push_back(token.to_json());
  return json_response(200, {{"tokens", tokens}});
}

Response revoke_token(const Call& call) {
  reachable_token(call, call.params[0]);
  return json_response(200, call.store.revoke_token(call.params[0]).to_json());
}

Response list_projects(const Call& call) {
  nlohmann::json projects = nlohmann::json::array();
  for (const proto::Project& project : call.store.list_projects())
    if (call.principal.reaches(project.name))
      projects.push_back(with_usage(call, project).to_json());
  return json_response(200, {{"projects", projects}});
}

Response get_project(const Call& call) {
  const std::string& name = call.params[0];
  const std::string message = "project " + name + " not found";
  require_reach(call, name, message);
  for (const proto::Project& project : call.store.list_projects())
    if (project.name == name) return json_response(200, with_usage(call, project).to_json());
  throw ApiException(404, "not_found", message);
}

// {"quota_bytes": N} (0 = no quota); creates the project when new.
Response put_project(const Call& call) {
  const std::string& name = call.params[0];
  if (!call.principal.all_projects())
    throw ApiException(403, "forbidden", "only an admin token of every project ('*') sets quotas");
  proto::validate_project_name(name, "project in path");
  nlohmann::json body = parse_json_body(call.request);
  proto::FieldReader reader(body, "");
  reader.reject_unknown({"quota_bytes"});
  const int64_t quota = reader.optional<int64_t>("quota_bytes", 0);
  if (quota < 0) throw ApiException(400, "invalid_field", "quota_bytes: expected bytes >= 0");
  return json_response(200, with_usage(call, call.store.set_project_quota(name, quota)).to_json());
}

}  // namespace keel::server::routes
