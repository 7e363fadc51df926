// Jobs: create (Idempotency-Key), list, get, log, cancel, retry, reprocess, artifacts (and the
// members of tar artifacts).
#include <algorithm>
#include <chrono>

#include "proto/job.h"
#include "proto/worker_protocol.h"
#include "server/api_response.h"
#include "server/file_response.h"
#include "server/job_events.h"
#include "server/routes.h"
#include "server/tar_index.h"

namespace keel::server::routes {

namespace {

constexpr size_t kMaxIdempotencyKey = 200;

}  // namespace

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

namespace {

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

// The job, when the token reaches its project (404 otherwise, as for an unknown id).
proto::Job reachable_job(const Call& call, const std::string& job_id) {
  proto::Job job = call.store.get_job(job_id);
  require_reach(call, job.project, "job " + job_id + " not found");
  return job;
}

}  // namespace

Response create_job(const Call& call) {
  proto::JobRequest request = proto::JobRequest::from_json(parse_json_body(call.request));
  request.project = request_project(call, request.project);
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
  filter.batch_id = query_string(call, "batch_id");
  filter.mission_name = query_string(call, "mission_name");
  filter.project = listing_project(call);
  filter.limit = static_cast<int>(query_int(call, "limit", filter.limit, 1, 10000));
  return json_response(200, {{"jobs", jobs_json(call.store.list_jobs(filter))}});
}

Response get_job(const Call& call) {
  return json_response(200, reachable_job(call, call.params[0]).to_json());
}

Response read_job_log(const Call& call) {
  const std::string& id = call.params[0];
  int64_t from = query_int(call, "from", 0, 0, INT64_MAX);
  int limit = static_cast<int>(query_int(call, "limit", 1000, 1, 10000));
  reachable_job(call, id);  // 404 for an unknown job rather than an empty page
  return json_response(200, call.store.read_log(id, from, limit).to_json());
}

Response cancel_job(const Call& call) {
  reachable_job(call, call.params[0]);
  return json_response(200, call.store.cancel_job(call.params[0]).to_json());
}

Response retry_job(const Call& call) {
  reachable_job(call, call.params[0]);
  return json_response(200, call.store.retry_job(call.params[0]).to_json());
}

// One new job per matching stored mission of the token's project, made in one transaction
// (storage: create_batch); every listed id is checked before any job is made.
Response reprocess(const Call& call) {
  proto::ReprocessRequest request =
      proto::ReprocessRequest::from_json(parse_json_body(call.request));
  if (!request.mission_ids.empty() && !request.name_prefix.empty())
    throw ApiException(400, "invalid_field", "give mission_ids or name_prefix, not both");
  request.project = request_project(call, request.project);
  const proto::Batch batch = call.store.create_batch(request);
  storage::JobFilter filter;
  filter.batch_id = batch.id;
  // Listing a large batch would cost more than making it (10,000 jobs: ~0.7 s to make, ~7 s
  // to list and encode at load 14): over 1,000 jobs the answer is the batch alone, at once.
  filter.limit = 1000;
  std::vector<proto::Job> jobs;
  if (batch.jobs <= filter.limit) jobs = call.store.list_jobs(filter);
  // Oldest first, as the missions were given; a batch over 1,000 jobs lists none here
  // (GET /v1/jobs?batch_id= pages through them; keel jobs --batch follows it).
  std::reverse(jobs.begin(), jobs.end());
  return json_response(201, {{"batch", batch.to_json()}, {"jobs", jobs_json(jobs)}});
}

Response get_batch(const Call& call) {
  const proto::Batch batch = call.store.get_batch(call.params[0]);
  require_reach(call, batch.project, "batch " + call.params[0] + " not found");
  return json_response(200, batch.to_json());
}

Response job_events(const Call& call) {
  JobEventsOptions options;
  options.job_id = query_string(call, "job_id");
  if (!options.job_id.empty()) reachable_job(call, options.job_id);
  options.now_ms = call.options.wall_clock_ms ? call.options.wall_clock_ms : storage::system_clock_ms;
  Response response;
  response.status = 200;
  response.headers.set("Content-Type", "text/event-stream");
  response.headers.set("Cache-Control", "no-store");
  response.headers.set("X-Accel-Buffering", "no");  // nginx: pass events through at once
  response.stream = std::make_shared<JobEvents>(call.store, call.principal, options);
  return response;
}

Response queue_summary(const Call& call) {
  return json_response(200, call.store.queue_summary().to_json());
}

Response list_job_artifacts(const Call& call) {
  const std::string& id = call.params[0];
  reachable_job(call, id);  // 404 for an unknown job rather than an empty list
  nlohmann::json artifacts = nlohmann::json::array();
  for (const auto& artifact : call.store.list_artifacts(id))
    artifacts.push_back(artifact.to_json());
  return json_response(200, {{"artifacts", artifacts}});
}

Response get_artifact_file(const Call& call) {
  proto::Artifact artifact = call.store.get_artifact(call.params[0]);
  require_reach(call, artifact.project, "artifact " + call.params[0] + " not found");
  const std::string& member = call.params[1];
  const auto path = call.store.blob_path(artifact.sha256);
  const auto size = static_cast<uint64_t>(call.store.blob_size(artifact.sha256));
  std::shared_ptr<const TarIndex> index;
  try {
    index = cached_tar_index(artifact.sha256, path, size, "artifact '" + artifact.name + "'");
  } catch (const TarIndexError& e) {
    throw ApiException(404, "not_found", std::string(e.what()) + ": it has no files to serve");
  }
  const auto found = index->find(member);
  if (found == index->end())
    throw ApiException(404, "not_found",
                       "artifact '" + artifact.name + "' has no member '" + member + "'");
  StoredFile file;
  file.path = path;
  file.offset = found->second.offset;
  file.size = found->second.size;
  // Unique per member of this content (the tar never changes), and free of quotes.
  file.sha256 = artifact.sha256 + ":" + std::to_string(found->second.offset);
  file.content_type = content_type_for(member);
  file.download_name = member.substr(member.find_last_of('/') + 1);
  return file_response(call.request, file);
}

Response get_artifact(const Call& call) {
  proto::Artifact artifact = call.store.get_artifact(call.params[0]);
  require_reach(call, artifact.project, "artifact " + call.params[0] + " not found");
  StoredFile file;
  file.path = call.store.blob_path(artifact.sha256);
  file.size = static_cast<uint64_t>(call.store.blob_size(artifact.sha256));
  file.sha256 = artifact.sha256;
  file.content_type = content_type_for(artifact.name);
  file.download_name = artifact.name;
  return file_response(call.request, file);
}

}  // namespace keel::server::routes
