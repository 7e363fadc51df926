// Route functions of the API, one file per resource (routes_*.cc). Internal to the server:
// http_handler.cc matches a request to one of these and maps exceptions to error answers.
#pragma once

#include <string>
#include <vector>

#include "proto/auth.h"
#include "server/http_handler.h"
#include "server/http_types.h"
#include "server/url.h"
#include "storage/store.h"

namespace keel::server::routes {

struct Call {
  storage::Store& store;
  const Request& request;
  const Target& target;
  const std::vector<std::string>& params;  // path parameters ("{id}", "{stage}") in order
  const HandlerOptions& options;
  const RequestCounters& counters;
  const proto::TokenInfo& principal;  // the bearer token's record (empty for open routes)
};

using RouteFn = Response (*)(const Call&);

// routes_health.cc
Response healthz(const Call& call);
Response metrics(const Call& call);

// routes_uploads.cc
Response create_upload(const Call& call);
Response head_upload(const Call& call);
Response get_upload(const Call& call);
Response put_upload_chunk(const Call& call);
Response complete_upload(const Call& call);
Response delete_upload(const Call& call);
Response get_blob(const Call& call);

// routes_missions.cc
Response create_mission(const Call& call);
Response list_missions(const Call& call);
Response get_mission(const Call& call);

// routes_jobs.cc
Response create_job(const Call& call);
Response list_jobs(const Call& call);
Response get_job(const Call& call);
Response read_job_log(const Call& call);
Response cancel_job(const Call& call);
Response retry_job(const Call& call);
Response reprocess(const Call& call);
Response list_job_artifacts(const Call& call);
Response get_artifact(const Call& call);
Response get_artifact_file(const Call& call);  // a member of a tar artifact

Response get_batch(const Call& call);
Response job_events(const Call& call);
Response queue_summary(const Call& call);

// routes_comparisons.cc (issue 16)
Response create_comparison(const Call& call);
// The request's Idempotency-Key (routes_jobs.cc); 400 when too long or not visible ASCII.
std::string idempotency_key(const Request& request);

// routes_worker.cc
Response worker_lease(const Call& call);
Response worker_release_job(const Call& call);
Response worker_heartbeat(const Call& call);
Response worker_add_artifact(const Call& call);
Response worker_complete_stage(const Call& call);
Response worker_complete_job(const Call& call);
Response worker_fail_job(const Call& call);

// routes_web.cc: the dashboard's files for any GET/HEAD outside /v1 that no route above takes.
Response web_file(const Call& call);

// routes_admin.cc
Response create_token(const Call& call);
Response list_tokens(const Call& call);
Response revoke_token(const Call& call);
Response list_projects(const Call& call);
Response get_project(const Call& call);
Response put_project(const Call& call);

// Projects (storage/store.h): another project's object answers 404 with the same message
// as an unknown id, so ids leak nothing. `not_found_message` is that message.
void require_reach(const Call& call, const std::string& project,
                   const std::string& not_found_message);
// The project a create request lands in: the token's, or for a token of every project the
// one the request names ("" = default). 404 when a project token names another project.
std::string request_project(const Call& call, const std::string& requested);
// The project filter for listings: the token's ("*" = every project).
std::string listing_project(const Call& call);

// Storage limits: 507 insufficient_storage when storing `bytes` more would leave less than
// the free-space reserve; 413 quota_exceeded when the project would hold more than its quota.
// `what` names the thing refused ("upload 'm.tar'").
void require_space(const Call& call, int64_t bytes, const std::string& what);
void require_quota(const Call& call, const std::string& project, int64_t bytes,
                   const std::string& what);

// Query helpers shared by route files: ApiException 400 `invalid_field` on bad values.
int64_t query_int(const Call& call, const std::string& name, int64_t fallback, int64_t min,
                  int64_t max);
std::string query_string(const Call& call, const std::string& name);

}  // namespace keel::server::routes
