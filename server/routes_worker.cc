// The worker protocol: lease, heartbeat, artifact registration, stage completion, finish.
// A Conflict from the store here means the caller's lease is no longer the job's current
// one: 409 `lease_lost`, so the worker drops the job.
#include <chrono>

#include "proto/options.h"
#include "proto/worker_protocol.h"
#include "server/api_response.h"
#include "server/lease_wait.h"
#include "server/routes.h"

namespace keel::server::routes {

namespace {

// A worker token of one project works only that project's jobs: another project's job
// answers 404, as for an unknown id.
void require_job_reach(const Call& call, const std::string& job_id) {
  require_reach(call, call.store.get_job(job_id).project, "job " + job_id + " not found");
}

template <typename Fn>
auto with_lease(Fn&& fn) -> decltype(fn()) {
  try {
    return fn();
  } catch (const storage::Conflict& e) {
    throw ApiException(409, "lease_lost", e.what());
  }
}

}  // namespace

Response worker_lease(const Call& call) {
  proto::LeaseRequest request = proto::LeaseRequest::from_json(parse_json_body(call.request));
  if (request.worker.empty())
    throw ApiException(400, "invalid_field", "worker: expected a non-empty name");
  if (request.lease_seconds < 1 || request.lease_seconds > 3600)
    throw ApiException(
        400, "invalid_field",
        "lease_seconds: expected 1..3600, got " + std::to_string(request.lease_seconds));
  request.project = call.principal.project;
  if (auto answer = try_lease(call.store, request)) return *answer;
  if (request.wait_seconds == 0) return empty_response(204);
  Response response;
  response.pending = std::make_shared<LeaseWait>(
      call.store, request,
      std::chrono::steady_clock::now() + std::chrono::seconds(request.wait_seconds));
  return response;
}

Response worker_release_job(const Call& call) {
  proto::JobFinish release = proto::JobFinish::from_json(parse_json_body(call.request));
  require_job_reach(call, call.params[0]);
  return with_lease([&] {
    return json_response(200, call.store.release_job(call.params[0], release.lease_id).to_json());
  });
}

Response worker_heartbeat(const Call& call) {
  proto::Heartbeat beat = proto::Heartbeat::from_json(parse_json_body(call.request));
  if (!(beat.progress >= 0.0 && beat.progress <= 1.0))
    throw ApiException(400, "invalid_field", "progress: expected a number in [0, 1]");
  require_job_reach(call, call.params[0]);
  return with_lease(
      [&] { return json_response(200, call.store.heartbeat(call.params[0], beat).to_json()); });
}

Response worker_add_artifact(const Call& call) {
  proto::ArtifactRegistration registration =
      proto::ArtifactRegistration::from_json(parse_json_body(call.request));
  if (!proto::is_known_stage(registration.stage))
    throw ApiException(400, "invalid_field", "stage: unknown stage '" + registration.stage + "'");
  if (!proto::is_sha256_hex(registration.blob))
    throw ApiException(400, "invalid_field", "blob: expected 64 lowercase hex digits");
  if (!call.store.has_blob(registration.blob) ||
      (!call.principal.all_projects() &&
       !call.store.project_has_blob(call.principal.project, registration.blob)))
    throw ApiException(404, "not_found",
                       "blob: no blob " + registration.blob + " (upload it first)");
  require_job_reach(call, call.params[0]);
  // A blob new to the job's project counts against its quota (the upload may have been
  // skipped because another project holds the same bytes).
  const std::string project = call.store.get_job(call.params[0]).project;
  if (!call.store.project_has_blob(project, registration.blob))
    require_quota(call, project, call.store.blob_size(registration.blob),
                  "artifact '" + registration.name + "'");
  return with_lease([&] {
    return json_response(201, call.store.add_artifact(call.params[0], registration).to_json());
  });
}

Response worker_complete_stage(const Call& call) {
  const std::string& stage = call.params[1];
  if (!proto::is_known_stage(stage))
    throw ApiException(400, "invalid_field", "stage in path: unknown stage '" + stage + "'");
  proto::StageCompletion completion =
      proto::StageCompletion::from_json(parse_json_body(call.request));
  if (!(completion.seconds >= 0.0))
    throw ApiException(400, "invalid_field", "seconds: expected a duration >= 0");
  require_job_reach(call, call.params[0]);
  with_lease([&] {
    call.store.complete_stage(call.params[0], stage, completion);
    return 0;
  });
  return empty_response(204);
}

Response worker_complete_job(const Call& call) {
  proto::JobFinish finish = proto::JobFinish::from_json(parse_json_body(call.request));
  require_job_reach(call, call.params[0]);
  return with_lease([&] {
    return json_response(200, call.store.finish_job(call.params[0], finish, true).to_json());
  });
}

Response worker_fail_job(const Call& call) {
  proto::JobFinish finish = proto::JobFinish::from_json(parse_json_body(call.request));
  if (finish.error.empty())
    throw ApiException(400, "invalid_field", "error: expected a message saying why the job failed");
  require_job_reach(call, call.params[0]);
  return with_lease([&] {
    return json_response(200, call.store.finish_job(call.params[0], finish, false).to_json());
  });
}

}  // namespace keel::server::routes
