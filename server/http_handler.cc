#include "server/http_handler.h"

#include <spdlog/spdlog.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <system_error>

#include "proto/contract_error.h"
#include "server/api_response.h"
#include "server/routes.h"
#include "server/url.h"

namespace keel::server {

namespace {

// Who may call a route: a set of roles (docs/api.md, "Who may do what"). Open routes
// (/healthz, /metrics) need no token; every /v1 route names its roles, and a token of
// another role is answered 403 before anything is looked up (so a 403 says nothing about
// whether an object exists).
enum RoleBit : unsigned {
  kOpen = 0,
  kAdmin = 1u << static_cast<unsigned>(proto::Role::kAdmin),
  kSubmitter = 1u << static_cast<unsigned>(proto::Role::kSubmitter),
  kViewer = 1u << static_cast<unsigned>(proto::Role::kViewer),
  kWorker = 1u << static_cast<unsigned>(proto::Role::kWorker),
};
constexpr unsigned kReaders = kAdmin | kSubmitter | kViewer;    // read jobs, logs, artifacts
constexpr unsigned kWriters = kAdmin | kSubmitter;              // create, cancel, retry
constexpr unsigned kUploaders = kAdmin | kSubmitter | kWorker;  // uploads (worker artifacts)
constexpr unsigned kWorkers = kAdmin | kWorker;                 // the worker protocol

struct Route {
  const char* method;
  const char* pattern;  // segments separated by '/', "*" matches one path parameter
  routes::RouteFn fn;
  unsigned roles;
};

// Order matters only for readability: patterns do not overlap. "**" (last) matches the rest of
// the path, one segment or more, joined by '/'.
const Route kRoutes[] = {
    {"GET", "healthz", routes::healthz, kOpen},
    {"GET", "metrics", routes::metrics, kOpen},
    {"POST", "v1/uploads", routes::create_upload, kUploaders},
    {"HEAD", "v1/uploads/*", routes::head_upload, kUploaders},
    {"GET", "v1/uploads/*", routes::get_upload, kUploaders},
    {"PUT", "v1/uploads/*", routes::put_upload_chunk, kUploaders},
    {"DELETE", "v1/uploads/*", routes::delete_upload, kUploaders},
    {"POST", "v1/uploads/*/complete", routes::complete_upload, kUploaders},
    {"GET", "v1/blobs/*", routes::get_blob, kUploaders},
    {"POST", "v1/missions", routes::create_mission, kWriters},
    {"GET", "v1/missions", routes::list_missions, kReaders},
    {"GET", "v1/missions/*", routes::get_mission, kReaders},
    {"POST", "v1/jobs", routes::create_job, kWriters},
    {"POST", "v1/comparisons", routes::create_comparison, kWriters},
    {"GET", "v1/jobs", routes::list_jobs, kReaders},
    {"GET", "v1/jobs/*", routes::get_job, kReaders},
    {"GET", "v1/jobs/*/log", routes::read_job_log, kReaders},
    {"POST", "v1/jobs/*/cancel", routes::cancel_job, kWriters},
    {"POST", "v1/jobs/*/retry", routes::retry_job, kWriters},
    {"GET", "v1/jobs/*/artifacts", routes::list_job_artifacts, kReaders},
    {"POST", "v1/reprocess", routes::reprocess, kWriters},
    {"GET", "v1/artifacts/*", routes::get_artifact, kReaders | kWorker},
    {"GET", "v1/artifacts/*/files/**", routes::get_artifact_file, kReaders | kWorker},
    {"GET", "v1/batches/*", routes::get_batch, kReaders},
    {"GET", "v1/events", routes::job_events, kReaders},
    {"GET", "v1/queue", routes::queue_summary, kReaders},
    {"POST", "v1/worker/lease", routes::worker_lease, kWorkers},
    {"POST", "v1/worker/jobs/*/release", routes::worker_release_job, kWorkers},
    {"POST", "v1/worker/jobs/*/heartbeat", routes::worker_heartbeat, kWorkers},
    {"POST", "v1/worker/jobs/*/artifacts", routes::worker_add_artifact, kWorkers},
    {"POST", "v1/worker/jobs/*/stages/*/complete", routes::worker_complete_stage, kWorkers},
    {"POST", "v1/worker/jobs/*/complete", routes::worker_complete_job, kWorkers},
    {"POST", "v1/worker/jobs/*/fail", routes::worker_fail_job, kWorkers},
    {"POST", "v1/tokens", routes::create_token, kAdmin},
    {"GET", "v1/tokens", routes::list_tokens, kAdmin},
    {"POST", "v1/tokens/*/revoke", routes::revoke_token, kAdmin},
    {"GET", "v1/projects", routes::list_projects, kReaders},
    {"GET", "v1/projects/*", routes::get_project, kReaders},
    {"PUT", "v1/projects/*", routes::put_project, kAdmin},
};

bool role_allowed(unsigned roles, proto::Role role) {
  return (roles & (1u << static_cast<unsigned>(role))) != 0;
}

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

Response insufficient_storage(const std::string& detail) {
  spdlog::warn("refused for lack of space: {}", detail);
  return error_response(
      507, "insufficient_storage",
      "the server is out of disk space; nothing of this request was kept (" + detail + ")");
}

bool starts_with_v1(const std::vector<std::string>& segments) {
  return !segments.empty() && segments[0] == "v1";
}

}  // namespace

HttpHandler::HttpHandler(storage::Store& store, HandlerOptions options)
    : store_(store), options_(std::move(options)), limiter_(options_.rate_limit) {}

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
  } catch (const storage::StorageFull& e) {
    response = insufficient_storage(e.what());
  } catch (const std::system_error& e) {
    if (e.code() == std::errc::no_space_on_device || e.code().value() == EDQUOT) {
      response = insufficient_storage(e.what());
    } else {
      spdlog::error("{} {}: unexpected error: {}", request.method, request.target, e.what());
      response = error_response(500, "internal", std::string("internal error: ") + e.what());
    }
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
    const double now_s =
        options_.monotonic_s
            ? options_.monotonic_s()
            : std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch())
                  .count();
    if (const std::optional<double> wait = limiter_.take(principal.id, now_s)) {
      const auto seconds = static_cast<int64_t>(std::ceil(*wait));
      Headers headers;
      headers.set("Retry-After", std::to_string(std::max<int64_t>(1, seconds)));
      throw ApiException(429, "rate_limited",
                         "token " + principal.id + " made more than " +
                             std::to_string(static_cast<int64_t>(options_.rate_limit.rate_per_s)) +
                             " requests per second (bursts of " +
                             std::to_string(static_cast<int64_t>(options_.rate_limit.burst)) +
                             "); retry after " + std::to_string(std::max<int64_t>(1, seconds)) +
                             " s",
                         headers);
    }
  }
  std::vector<std::string> params;
  std::string allowed;
  for (const Route& route : kRoutes) {
    if (!match(route.pattern, target->segments, params)) continue;
    if (request.method == route.method) {
      if (route.roles != kOpen && !role_allowed(route.roles, principal.role))
        throw ApiException(403, "forbidden",
                           "a " + proto::to_string(principal.role) + " token may not " +
                               request.method + " " + target->path);
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

void require_space(const Call& call, int64_t bytes, const std::string& what) {
  if (!call.options.free_bytes) return;
  const int64_t free = call.options.free_bytes();
  if (free < 0 || free - bytes >= call.options.min_free_bytes) return;  // unknown: no check
  throw ApiException(507, "insufficient_storage",
                     what + " of " + std::to_string(bytes) +
                         " bytes refused: the server's disk has " + std::to_string(free) +
                         " bytes free and keeps " + std::to_string(call.options.min_free_bytes) +
                         " in reserve; try again when space was freed");
}

void require_quota(const Call& call, const std::string& project, int64_t bytes,
                   const std::string& what) {
  const std::string name = project.empty() ? proto::kDefaultProject : project;
  int64_t quota = 0;
  for (const proto::Project& p : call.store.list_projects())
    if (p.name == name) quota = p.quota_bytes;
  if (quota <= 0) return;
  const int64_t used = call.store.project_usage(name);
  if (used + bytes <= quota) return;
  throw ApiException(413, "quota_exceeded",
                     what + " of " + std::to_string(bytes) + " bytes refused: project " + name +
                         " holds " + std::to_string(used) + " of its quota of " +
                         std::to_string(quota) + " bytes");
}

std::string query_string(const Call& call, const std::string& name) {
  auto it = call.target.query.find(name);
  return it == call.target.query.end() ? std::string() : it->second;
}

}  // namespace routes

}  // namespace keel::server
