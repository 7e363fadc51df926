// POST /v1/missions (checks the bundle tar first), GET /v1/missions[?prefix=], GET
// /v1/missions/{id}.
#include "proto/resources.h"
#include "server/api_response.h"
#include "server/bundle_check.h"
#include "server/routes.h"

namespace keel::server::routes {

namespace {

// The blob must exist and, for a token of one project, be its project's (uploaded there):
// a mission cannot be made of another project's bytes.
void require_blob(const Call& call, const std::string& project, const std::string& field,
                  const std::string& sha256) {
  if (!call.store.has_blob(sha256) ||
      (!call.principal.all_projects() && !call.store.project_has_blob(project, sha256)))
    throw ApiException(404, "not_found", field + ": no blob " + sha256 + " (upload it first)");
}

}  // namespace

Response create_mission(const Call& call) {
  proto::MissionRequest request = proto::MissionRequest::from_json(parse_json_body(call.request));
  request.project = request_project(call, request.project);
  const std::string project = request.project.empty() ? proto::kDefaultProject : request.project;
  require_blob(call, project, "bundle_blob", request.bundle_blob);
  if (!request.cad_blob.empty()) require_blob(call, project, "cad_blob", request.cad_blob);
  try {
    check_mission_bundle(call.store.blob_path(request.bundle_blob));
  } catch (const BundleError& e) {
    throw ApiException(400, e.code(), "bundle_blob " + request.bundle_blob + ": " + e.what());
  }
  return json_response(201, call.store.create_mission(request).to_json());
}

Response list_missions(const Call& call) {
  nlohmann::json missions = nlohmann::json::array();
  for (const auto& mission :
       call.store.list_missions(query_string(call, "prefix"), listing_project(call)))
    missions.push_back(mission.to_json());
  return json_response(200, {{"missions", missions}});
}

Response get_mission(const Call& call) {
  const proto::Mission mission = call.store.get_mission(call.params[0]);
  require_reach(call, mission.project, "mission " + mission.id + " not found");
  return json_response(200, mission.to_json());
}

}  // namespace keel::server::routes
