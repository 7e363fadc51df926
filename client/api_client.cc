// ApiClient: requests, JSON helpers and the typed client/worker calls. Uploads and
// downloads are in api_client_upload.cc and api_client_download.cc.
#include "client/api_client.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <thread>

#include "client/api_client_connection.h"
#include "client/http_url.h"
#include "proto/api_error.h"
#include "proto/contract_error.h"

namespace keel::client {

namespace {

constexpr const char* kUserAgent = "keel-client/0.1";

std::optional<http::verb> verb_of(const std::string& method) {
  const http::verb verb = http::string_to_verb(method);
  if (verb == http::verb::unknown) return std::nullopt;
  return verb;
}

std::string lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

template <class Body>
HttpResult to_result(const http::response<Body>& response) {
  HttpResult out;
  out.status = static_cast<int>(response.result_int());
  for (const auto& field : response)
    out.headers[lower(std::string(field.name_string()))] = std::string(field.value());
  return out;
}

bool is_success(int status) { return status >= 200 && status < 300; }

// Parses a typed answer; a malformed one is the server's fault, named with the request.
template <class T>
T parse_answer(const nlohmann::json& body, const std::string& what) {
  try {
    return T::from_json(body, "");
  } catch (const proto::ContractError& e) {
    throw ApiCallError(0, "bad_response", what + ": unexpected answer: " + e.what());
  }
}

template <class T>
std::vector<T> parse_list(const nlohmann::json& body, const char* field, const std::string& what) {
  if (!body.is_object() || !body.contains(field) || !body[field].is_array())
    throw ApiCallError(0, "bad_response",
                       what + ": unexpected answer: expected {\"" + field + "\": [...]}");
  std::vector<T> out;
  for (size_t i = 0; i < body[field].size(); ++i) {
    try {
      out.push_back(
          T::from_json(body[field][i], std::string(field) + "[" + std::to_string(i) + "]"));
    } catch (const proto::ContractError& e) {
      throw ApiCallError(0, "bad_response", what + ": unexpected answer: " + e.what());
    }
  }
  return out;
}

std::string encode_path(const std::string& id) { return url_encode(id); }

}  // namespace

ApiCallError error_from_answer(const HttpResult& result, const std::string& what) {
  nlohmann::json body = nlohmann::json::parse(result.body, nullptr, /*allow_exceptions=*/false);
  if (!body.is_discarded() && body.is_object() && body.contains("error")) {
    try {
      const proto::ApiError error = proto::ApiError::from_json(body);
      return ApiCallError(result.status, error.code, error.message);
    } catch (const proto::ContractError&) {
      // Falls through to the generic message below.
    }
  }
  std::string text = result.body.substr(0, 200);
  if (text.empty()) text = "HTTP " + std::to_string(result.status);
  return ApiCallError(result.status, "http_" + std::to_string(result.status), what + ": " + text);
}

ApiClient::ApiClient(ClientConfig config) : config_(std::move(config)) {
  connection_ = std::make_unique<Connection>(parse_base_url(config_.url), config_.timeout_s, stats_,
                                             config_.token, config_.ca_file);
}

ApiClient::~ApiClient() = default;

HttpResult ApiClient::request(const std::string& method, const std::string& target,
                              const std::string& body,
                              const std::map<std::string, std::string>& headers) {
  const auto verb = verb_of(method);
  if (!verb) throw std::invalid_argument("unknown HTTP method '" + method + "'");
  http::request<http::string_body> req{*verb, connection_->target(target), 11};
  connection_->prepare(req, headers);
  if (!body.empty() && !headers.count("Content-Type"))
    req.set(http::field::content_type, "application/json");
  req.body() = body;
  req.prepare_payload();
  http::response<http::string_body> response = connection_->exchange(req);
  HttpResult out = to_result(response);
  out.body = std::move(response.body());
  return out;
}

void ApiClient::Connection::prepare(http::fields& fields,
                                    const std::map<std::string, std::string>& headers) const {
  fields.set(http::field::host, url().host + ":" + url().port);
  fields.set(http::field::user_agent, kUserAgent);
  if (!token.empty()) fields.set(http::field::authorization, "Bearer " + token);
  for (const auto& [name, value] : headers) fields.set(name, value);
}

HttpResult ApiClient::request_or_throw(const std::string& method, const std::string& target,
                                       const std::string& body,
                                       const std::map<std::string, std::string>& headers) {
  HttpResult result = request(method, target, body, headers);
  if (!is_success(result.status))
    throw error_from_answer(result, connection_->describe(method, target));
  return result;
}

nlohmann::json ApiClient::get_json(const std::string& target) {
  const HttpResult result = request_or_throw("GET", target, "", {});
  return parse_json_body(result, connection_->describe("GET", target));
}

nlohmann::json ApiClient::post_json(const std::string& target, const nlohmann::json& body,
                                    const std::map<std::string, std::string>& headers) {
  const HttpResult result = request_or_throw("POST", target, body.dump(), headers);
  return parse_json_body(result, connection_->describe("POST", target));
}

nlohmann::json parse_json_body(const HttpResult& result, const std::string& what) {
  if (result.status == 204 || result.body.empty()) return nlohmann::json();
  nlohmann::json body = nlohmann::json::parse(result.body, nullptr, /*allow_exceptions=*/false);
  if (body.is_discarded())
    throw ApiCallError(0, "bad_response",
                       what + ": answer is not JSON: " + result.body.substr(0, 200));
  return body;
}

void ApiClient::pause_before_retry(int failures) const {
  const double seconds = std::min(5.0, config_.retry_backoff_s * (1 << std::min(failures - 1, 10)));
  if (seconds > 0) std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
}

// --- client API ---

proto::Mission ApiClient::create_mission(const proto::MissionRequest& request) {
  return parse_answer<proto::Mission>(post_json("/v1/missions", request.to_json()),
                                      "POST /v1/missions");
}

std::vector<proto::Mission> ApiClient::list_missions(const std::string& prefix) {
  std::string target = "/v1/missions";
  if (!prefix.empty()) target += "?prefix=" + url_encode(prefix);
  return parse_list<proto::Mission>(get_json(target), "missions", "GET " + target);
}

proto::Job ApiClient::create_job(const proto::JobRequest& request,
                                 const std::string& idempotency_key) {
  std::map<std::string, std::string> headers;
  if (!idempotency_key.empty()) headers["Idempotency-Key"] = idempotency_key;
  return parse_answer<proto::Job>(post_json("/v1/jobs", request.to_json(), headers),
                                  "POST /v1/jobs");
}

proto::Job ApiClient::get_job(const std::string& job_id) {
  const std::string target = "/v1/jobs/" + encode_path(job_id);
  return parse_answer<proto::Job>(get_json(target), "GET " + target);
}

std::vector<proto::Job> ApiClient::list_jobs(const std::string& state) {
  std::string target = "/v1/jobs";
  if (!state.empty()) target += "?state=" + url_encode(state);
  return parse_list<proto::Job>(get_json(target), "jobs", "GET " + target);
}

proto::Job ApiClient::cancel_job(const std::string& job_id) {
  const std::string target = "/v1/jobs/" + encode_path(job_id) + "/cancel";
  return parse_answer<proto::Job>(post_json(target, nlohmann::json::object()), "POST " + target);
}

proto::Job ApiClient::retry_job(const std::string& job_id) {
  const std::string target = "/v1/jobs/" + encode_path(job_id) + "/retry";
  return parse_answer<proto::Job>(post_json(target, nlohmann::json::object()), "POST " + target);
}

ApiClient::Reprocessed ApiClient::reprocess(const proto::ReprocessRequest& request) {
  const nlohmann::json body = post_json("/v1/reprocess", request.to_json());
  Reprocessed out;
  if (body.is_object() && body.contains("batch")) {
    try {
      out.batch = proto::Batch::from_json(body["batch"], "batch");
    } catch (const proto::ContractError& e) {
      throw ApiCallError(0, "bad_response",
                         std::string("POST /v1/reprocess: unexpected answer: ") + e.what());
    }
  }
  out.jobs = parse_list<proto::Job>(body, "jobs", "POST /v1/reprocess");
  return out;
}

proto::Batch ApiClient::get_batch(const std::string& batch_id) {
  const std::string target = "/v1/batches/" + encode_path(batch_id);
  return parse_answer<proto::Batch>(get_json(target), "GET " + target);
}

std::vector<proto::Job> ApiClient::list_batch_jobs(const std::string& batch_id, int limit) {
  const std::string target =
      "/v1/jobs?batch_id=" + url_encode(batch_id) + "&limit=" + std::to_string(limit);
  return parse_list<proto::Job>(get_json(target), "jobs", "GET " + target);
}

proto::LogPage ApiClient::read_log(const std::string& job_id, int64_t from) {
  const std::string target =
      "/v1/jobs/" + encode_path(job_id) + "/log?from=" + std::to_string(from);
  return parse_answer<proto::LogPage>(get_json(target), "GET " + target);
}

std::vector<proto::Artifact> ApiClient::list_artifacts(const std::string& job_id) {
  const std::string target = "/v1/jobs/" + encode_path(job_id) + "/artifacts";
  return parse_list<proto::Artifact>(get_json(target), "artifacts", "GET " + target);
}

// --- worker API ---

std::optional<proto::Lease> ApiClient::lease(const proto::LeaseRequest& request) {
  const HttpResult result =
      request_or_throw("POST", "/v1/worker/lease", request.to_json().dump(), {});
  if (result.status == 204) return std::nullopt;
  return parse_answer<proto::Lease>(parse_json_body(result, "POST /v1/worker/lease"),
                                    "POST /v1/worker/lease");
}

proto::HeartbeatReply ApiClient::heartbeat(const std::string& job_id,
                                           const proto::Heartbeat& beat) {
  const std::string target = "/v1/worker/jobs/" + encode_path(job_id) + "/heartbeat";
  return parse_answer<proto::HeartbeatReply>(post_json(target, beat.to_json()), "POST " + target);
}

proto::Artifact ApiClient::register_artifact(const std::string& job_id,
                                             const proto::ArtifactRegistration& reg) {
  const std::string target = "/v1/worker/jobs/" + encode_path(job_id) + "/artifacts";
  return parse_answer<proto::Artifact>(post_json(target, reg.to_json()), "POST " + target);
}

void ApiClient::complete_stage(const std::string& job_id, const std::string& stage,
                               const proto::StageCompletion& completion) {
  post_json(
      "/v1/worker/jobs/" + encode_path(job_id) + "/stages/" + encode_path(stage) + "/complete",
      completion.to_json());
}

proto::Job ApiClient::release_job(const std::string& job_id, const std::string& lease_id) {
  const std::string target = "/v1/worker/jobs/" + encode_path(job_id) + "/release";
  proto::JobFinish release;
  release.lease_id = lease_id;
  return parse_answer<proto::Job>(post_json(target, release.to_json()), "POST " + target);
}

proto::Job ApiClient::finish_job(const std::string& job_id, const proto::JobFinish& finish,
                                 bool succeeded) {
  const std::string target =
      "/v1/worker/jobs/" + encode_path(job_id) + (succeeded ? "/complete" : "/fail");
  return parse_answer<proto::Job>(post_json(target, finish.to_json()), "POST " + target);
}

}  // namespace keel::client
