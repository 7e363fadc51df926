#include "server/http_handler.h"

#include <spdlog/spdlog.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cerrno>
#include <cstdlib>

#include "proto/contract_error.h"
#include "server/api_response.h"
#include "server/routes.h"
#include "server/url.h"

namespace keel::server {

namespace {

struct Route {
  const char* method;
  const char* pattern;  // segments separated by '/', "*" matches one path parameter
  routes::RouteFn fn;
};

// Order matters only for readability: patterns do not overlap. "**" (last) matches the rest of
// the path, one segment or more, joined by '/'.
const Route kRoutes[] = {
    {"GET", "healthz", routes::healthz},
    {"GET", "metrics", routes::metrics},
    {"POST", "v1/uploads", routes::create_upload},
    {"HEAD", "v1/uploads/*", routes::head_upload},
    {"GET", "v1/uploads/*", routes::get_upload},
    {"PUT", "v1/uploads/*", routes::put_upload_chunk},
    {"DELETE", "v1/uploads/*", routes::delete_upload},
    {"POST", "v1/uploads/*/complete", routes::complete_upload},
    {"GET", "v1/blobs/*", routes::get_blob},
    {"POST", "v1/missions", routes::create_mission},
    {"GET", "v1/missions", routes::list_missions},
    {"GET", "v1/missions/*", routes::get_mission},
    {"POST", "v1/jobs", routes::create_job},
    {"POST", "v1/comparisons", routes::create_comparison},
    {"GET", "v1/jobs", routes::list_jobs},
    {"GET", "v1/jobs/*", routes::get_job},
    {"GET", "v1/jobs/*/log", routes::read_job_log},
    {"POST", "v1/jobs/*/cancel", routes::cancel_job},
    {"POST", "v1/jobs/*/retry", routes::retry_job},
    {"GET", "v1/jobs/*/artifacts", routes::list_job_artifacts},
    {"POST", "v1/reprocess", routes::reprocess},
    {"GET", "v1/artifacts/*", routes::get_artifact},
    {"GET", "v1/artifacts/*/files/**", routes::get_artifact_file},
    {"GET", "v1/batches/*", routes::get_batch},
    {"GET", "v1/events", routes::job_events},
    {"GET", "v1/queue", routes::queue_summary},
    {"POST", "v1/worker/lease", routes::worker_lease},
    {"POST", "v1/worker/jobs/*/release", routes::worker_release_job},
    {"POST", "v1/worker/jobs/*/heartbeat", routes::worker_heartbeat},
    {"POST", "v1/worker/jobs/*/artifacts", routes::worker_add_artifact},
    {"POST", "v1/worker/jobs/*/stages/*/complete", routes::worker_complete_stage},
    {"POST", "v1/worker/jobs/*/complete", routes::worker_complete_job},
    {"POST", "v1/worker/jobs/*/fail", routes::worker_fail_job},
};

// Matches `segments` against a pattern, collecting "*" segments into `params`.
bool match(const char* pattern, const std::vector<std::string>& segments,
           std::vector<std::string>& params) {
  params.clear();
  std::string_view rest(pattern);
  size_t index = 0;
  while (!rest.empty()) {
    size_t slash = rest.find('/');
    std::string_view part = rest.substr(0, slash);
    rest = slash == std::string_view::npos ? std::string_view() : rest.substr(slash + 1);
    if (index >= segments.size()) return false;
    if (part == "**") {
      std::string tail = segments[index];
      for (size_t k = index + 1; k < segments.size(); ++k) tail += "/" + segments[k];
      params.push_back(tail);
      return true;
    }
    if (part == "*")
      params.push_back(segments[index]);
    else if (part != segments[index])
      return false;
    ++index;
  }
  return index == segments.size();
}

bool starts_with_v1(const std::vector<std::string>& segments) {
  return !segments.empty() && segments[0] == "v1";
}

}  // namespace

HttpHandler::HttpHandler(storage::Store& store, HandlerOptions options)
    : store_(store), options_(std::move(options)) {}

HttpHandler::~HttpHandler() = default;

Response HttpHandler::handle(const Request& request) {
  Response response;
  try {
    response = dispatch(request);
  } catch (const ApiException& e) {
    response = error_response(e.status(), e.code(), e.what());
    for (const auto& [name, value] : e.headers().fields()) response.headers.set(name, value);
  } catch (const proto::ContractError& e) {
    response = error_response(400, "invalid_field", e.what());
  } catch (const storage::NotFound& e) {
    response = error_response(404, "not_found", e.what());
  } catch (const storage::Conflict& e) {
    response = error_response(409, "conflict", e.what());
  } catch (const storage::Invalid& e) {
    response = error_response(400, "invalid_field", e.what());
  } catch (const storage::Unavailable& e) {
    // The database is away (restart, network): nothing was lost, the client retries.
    spdlog::warn("{} {}: {}", request.method, request.target, e.what());
    response = error_response(503, "unavailable", e.what());
    response.headers.set("Retry-After", "2");
  } catch (const std::exception& e) {
    spdlog::error("{} {}: unexpected error: {}", request.method, request.target, e.what());
    response = error_response(500, "internal", std::string("internal error: ") + e.what());
  } catch (...) {
    spdlog::error("{} {}: unexpected non-standard exception", request.method, request.target);
    response = error_response(500, "internal", "internal error");
  }
  counters_.count(response.status);
  return response;
}

Response HttpHandler::dispatch(const Request& request) {
  std::optional<Target> target = parse_target(request.target);
  if (!target)
    throw ApiException(400, "bad_request",
                       "request target '" + request.target + "' is not a valid path");
  proto::TokenInfo principal;
  if (starts_with_v1(target->segments)) {
    std::optional<proto::TokenInfo> token = authorized(request);
    if (!token) {
      Headers challenge;
      challenge.set("WWW-Authenticate", "Bearer");
      throw ApiException(401, "unauthorized", "missing, unknown, expired or revoked bearer token",
                         challenge);
    }
    principal = std::move(*token);
  }
  std::vector<std::string> params;
  std::string allowed;
  for (const Route& route : kRoutes) {
    if (!match(route.pattern, target->segments, params)) continue;
    if (request.method == route.method) {
      routes::Call call{store_, request, *target, params, options_, counters_, principal};
      return route.fn(call);
    }
    allowed += (allowed.empty() ? "" : ", ") + std::string(route.method);
  }
  if (!allowed.empty()) {
    Headers headers;
    headers.set("Allow", allowed);
    throw ApiException(405, "method_not_allowed",
                       request.method + " " + target->path + ": allowed methods are " + allowed,
                       headers);
  }
  const bool reads = request.method == "GET" || request.method == "HEAD";
  if (reads && !starts_with_v1(target->segments)) {
    routes::Call call{store_, request, *target, params, options_, counters_, principal};
    return routes::web_file(call);
  }
  throw ApiException(404, "not_found", "no route " + request.method + " " + target->path);
}

std::optional<proto::TokenInfo> HttpHandler::authorized(const Request& request) {
  auto header = request.headers.get("Authorization");
  if (!header) return std::nullopt;
  std::string_view value(*header);
  constexpr std::string_view kScheme = "Bearer ";
  if (value.size() <= kScheme.size() || !iequals(value.substr(0, kScheme.size()), kScheme))
    return std::nullopt;
  std::string token(value.substr(kScheme.size()));
  while (!token.empty() && token.back() == ' ') token.pop_back();
  if (token.empty()) return std::nullopt;
  return store_.check_token(token);
}

uint64_t HttpHandler::body_limit(std::string_view method, std::string_view target) const {
  if (method == "PUT") {
    std::optional<Target> parsed = parse_target(target);
    std::vector<std::string> params;
    if (parsed && match("v1/uploads/*", parsed->segments, params)) return options_.max_chunk_bytes;
  }
  return options_.max_json_bytes;
}

namespace routes {

int64_t query_int(const Call& call, const std::string& name, int64_t fallback, int64_t min,
                  int64_t max) {
  auto it = call.target.query.find(name);
  if (it == call.target.query.end()) return fallback;
  const std::string& text = it->second;
  errno = 0;
  char* end = nullptr;
  long long value = std::strtoll(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || errno == ERANGE || value < min || value > max)
    throw ApiException(400, "invalid_field",
                       "query parameter " + name + "='" + text + "': expected an integer in [" +
                           std::to_string(min) + ", " + std::to_string(max) + "]");
  return value;
}

void require_reach(const Call& call, const std::string& project,
                   const std::string& not_found_message) {
  if (!call.principal.reaches(project)) throw ApiException(404, "not_found", not_found_message);
}

std::string request_project(const Call& call, const std::string& requested) {
  if (call.principal.all_projects()) return requested;
  if (!requested.empty() && requested != call.principal.project)
    throw ApiException(404, "not_found", "project " + requested + " not found");
  return call.principal.project;
}

std::string listing_project(const Call& call) { return call.principal.project; }

std::string query_string(const Call& call, const std::string& name) {
  auto it = call.target.query.find(name);
  return it == call.target.query.end() ? std::string() : it->second;
}

}  // namespace routes

}  // namespace keel::server
