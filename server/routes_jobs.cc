// Jobs: create (Idempotency-Key), list, get, log, cancel, retry, reprocess, artifacts.
#include "proto/job.h"
#include "proto/worker_protocol.h"
#include "server/api_response.h"
#include "server/file_response.h"
#include "server/routes.h"

namespace keel::server::routes {

namespace {

constexpr size_t kMaxIdempotencyKey = 200;

std::string idempotency_key(const Request& request) {
  std::string key = request.headers.get("Idempotency-Key").value_or("");
  if (key.size() > kMaxIdempotencyKey)
    throw ApiException(
        400, "invalid_field",
        "Idempotency-Key: longer than " + std::to_string(kMaxIdempotencyKey) + " characters");
  for (char c : key)
    if (static_cast<unsigned char>(c) < 0x21 || static_cast<unsigned char>(c) > 0x7e)
      throw ApiException(400, "invalid_field",
                         "Idempotency-Key: only visible ASCII characters are allowed");
  return key;
}

nlohmann::json jobs_json(const std::vector<proto::Job>& jobs) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& job : jobs) out.push_back(job.to_json());
  return out;
}

std::string content_type_for(const std::string& name) {
  auto ends_with = [&](const char* suffix) {
    std::string s(suffix);
    return name.size() >= s.size() && name.compare(name.size() - s.size(), s.size(), s) == 0;
  };
  if (ends_with(".json")) return "application/json";
  if (ends_with(".html")) return "text/html; charset=utf-8";
  if (ends_with(".tum") || ends_with(".txt") || ends_with(".csv"))
    return "text/plain; charset=utf-8";
  if (ends_with(".png")) return "image/png";
  return "application/octet-stream";
}

}  // namespace

Response create_job(const Call& call) {
  proto::JobRequest request = proto::JobRequest::from_json(parse_json_body(call.request));
  const std::string key = idempotency_key(call.request);
  bool created = true;
  proto::Job job = call.store.create_job(request, key, &created);
  return json_response(created ? 201 : 200, job.to_json());
}

Response list_jobs(const Call& call) {
  storage::JobFilter filter;
  std::string state = query_string(call, "state");
  if (!state.empty()) filter.state = proto::job_state_from_string(state, "query parameter state");
  filter.mission_id = query_string(call, "mission_id");
  filter.limit = static_cast<int>(query_int(call, "limit", filter.limit, 1, 10000));
  return json_response(200, {{"jobs", jobs_json(call.store.list_jobs(filter))}});
}

Response get_job(const Call& call) {
  return json_response(200, call.store.get_job(call.params[0]).to_json());
}

Response read_job_log(const Call& call) {
  const std::string& id = call.params[0];
  int64_t from = query_int(call, "from", 0, 0, INT64_MAX);
  int limit = static_cast<int>(query_int(call, "limit", 1000, 1, 10000));
  call.store.get_job(id);  // 404 for an unknown job rather than an empty page
  return json_response(200, call.store.read_log(id, from, limit).to_json());
}

Response cancel_job(const Call& call) {
  return json_response(200, call.store.cancel_job(call.params[0]).to_json());
}

Response retry_job(const Call& call) {
  return json_response(200, call.store.retry_job(call.params[0]).to_json());
}

// One new job per matching stored mission; every listed id is checked before any job is made.
Response reprocess(const Call& call) {
  proto::ReprocessRequest request =
      proto::ReprocessRequest::from_json(parse_json_body(call.request));
  if (!request.mission_ids.empty() && !request.name_prefix.empty())
    throw ApiException(400, "invalid_field", "give mission_ids or name_prefix, not both");
  std::vector<proto::Mission> missions;
  if (!request.mission_ids.empty()) {
    for (size_t i = 0; i < request.mission_ids.size(); ++i) {
      try {
        missions.push_back(call.store.get_mission(request.mission_ids[i]));
      } catch (const storage::NotFound&) {
        throw ApiException(
            404, "not_found",
            "mission_ids[" + std::to_string(i) + "]: no mission '" + request.mission_ids[i] + "'");
      }
    }
  } else {
    missions = call.store.list_missions(request.name_prefix);
  }
  std::vector<proto::Job> jobs;
  for (const auto& mission : missions) {
    proto::JobRequest job_request{mission.id, request.stages, request.options};
    jobs.push_back(call.store.create_job(job_request, ""));
  }
  return json_response(201, {{"jobs", jobs_json(jobs)}});
}

Response list_job_artifacts(const Call& call) {
  const std::string& id = call.params[0];
  call.store.get_job(id);  // 404 for an unknown job rather than an empty list
  nlohmann::json artifacts = nlohmann::json::array();
  for (const auto& artifact : call.store.list_artifacts(id))
    artifacts.push_back(artifact.to_json());
  return json_response(200, {{"artifacts", artifacts}});
}

Response get_artifact(const Call& call) {
  proto::Artifact artifact = call.store.get_artifact(call.params[0]);
  StoredFile file;
  file.path = call.store.blob_path(artifact.sha256);
  file.size = static_cast<uint64_t>(call.store.blob_size(artifact.sha256));
  file.sha256 = artifact.sha256;
  file.content_type = content_type_for(artifact.name);
  file.download_name = artifact.name;
  return file_response(call.request, file);
}

}  // namespace keel::server::routes
