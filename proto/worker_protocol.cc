#include "proto/worker_protocol.h"

#include "proto/contract_error.h"

namespace keel::proto {

namespace {
template <typename T>
std::vector<T> array_of(const FieldReader& r, const char* field) {
  std::vector<T> out;
  if (!r.has(field)) return out;
  const auto& items = r.at(field);
  if (!items.is_array())
    throw ContractError(r.child(field) + ": expected array, got " + json_type_name(items));
  for (size_t i = 0; i < items.size(); ++i)
    out.push_back(T::from_json(items[i], r.child(field) + "[" + std::to_string(i) + "]"));
  return out;
}

template <typename T>
nlohmann::json json_array(const std::vector<T>& items) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& item : items) out.push_back(item.to_json());
  return out;
}

nlohmann::json object_field(const FieldReader& r, const char* field) {
  nlohmann::json value = r.optional<nlohmann::json>(field, nlohmann::json::object());
  if (!value.is_object())
    throw ContractError(r.child(field) + ": expected object, got " + json_type_name(value));
  return value;
}
}  // namespace

nlohmann::json LeaseRequest::to_json() const {
  return {{"worker", worker}, {"lease_seconds", lease_seconds}, {"wait_seconds", wait_seconds}};
}

LeaseRequest LeaseRequest::from_json(const nlohmann::json& body, const std::string& path) {
  FieldReader r(body, path);
  r.reject_unknown({"worker", "lease_seconds", "wait_seconds"});
  LeaseRequest out;
  out.worker = r.required<std::string>("worker");
  out.lease_seconds = r.optional<int>("lease_seconds", 30);
  out.wait_seconds = r.optional<int>("wait_seconds", 0);
  if (out.lease_seconds < 1 || out.lease_seconds > 3600)
    throw ContractError(r.child("lease_seconds") + ": expected 1..3600 seconds");
  if (out.wait_seconds < 0 || out.wait_seconds > 30)
    throw ContractError(r.child("wait_seconds") + ": expected 0..30 seconds");
  return out;
}

nlohmann::json StageOutput::to_json() const {
  return {{"stage", stage},
          {"report", report},
          {"artifacts", json_array(artifacts)},
          {"seconds", seconds}};
}

StageOutput StageOutput::from_json(const nlohmann::json& body, const std::string& path) {
  FieldReader r(body, path);
  r.reject_unknown({"stage", "report", "artifacts", "seconds"});
  return {r.required<std::string>("stage"), object_field(r, "report"),
          array_of<Artifact>(r, "artifacts"), r.optional<double>("seconds", 0.0)};
}

nlohmann::json LeaseInput::to_json() const {
  return {{"job", job.to_json()}, {"artifacts", json_array(artifacts)}};
}

LeaseInput LeaseInput::from_json(const nlohmann::json& body, const std::string& path) {
  FieldReader r(body, path);
  r.reject_unknown({"job", "artifacts"});
  LeaseInput out;
  out.job = Job::from_json(r.at("job"), r.child("job"));
  out.artifacts = array_of<Artifact>(r, "artifacts");
  return out;
}

nlohmann::json Lease::to_json() const {
  nlohmann::json out = {{"lease_id", lease_id},
                        {"expires_at_ms", expires_at_ms},
                        {"job", job.to_json()},
                        {"mission", mission.to_json()},
                        {"completed", json_array(completed)}};
  if (!inputs.empty()) out["inputs"] = json_array(inputs);
  return out;
}

Lease Lease::from_json(const nlohmann::json& body, const std::string& path) {
  FieldReader r(body, path);
  r.reject_unknown({"lease_id", "expires_at_ms", "job", "mission", "completed", "inputs"});
  Lease out;
  out.lease_id = r.required<std::string>("lease_id");
  out.expires_at_ms = r.required<int64_t>("expires_at_ms");
  out.job = Job::from_json(r.at("job"), r.child("job"));
  out.mission = Mission::from_json(r.at("mission"), r.child("mission"));
  out.completed = array_of<StageOutput>(r, "completed");
  if (r.has("inputs")) out.inputs = array_of<LeaseInput>(r, "inputs");
  return out;
}

nlohmann::json Heartbeat::to_json() const {
  return {{"lease_id", lease_id}, {"stage", stage}, {"progress", progress}, {"log", log}};
}

Heartbeat Heartbeat::from_json(const nlohmann::json& body, const std::string& path) {
  FieldReader r(body, path);
  r.reject_unknown({"lease_id", "stage", "progress", "log"});
  Heartbeat out{r.required<std::string>("lease_id"), r.optional<std::string>("stage", ""),
                r.optional<double>("progress", 0.0),
                r.optional<std::vector<std::string>>("log", {})};
  if (!(out.progress >= 0.0 && out.progress <= 1.0))
    throw ContractError(r.child("progress") + ": expected a fraction in [0, 1]");
  return out;
}

nlohmann::json HeartbeatReply::to_json() const {
  return {{"canceled", canceled}, {"expires_at_ms", expires_at_ms}};
}

HeartbeatReply HeartbeatReply::from_json(const nlohmann::json& body, const std::string& path) {
  FieldReader r(body, path);
  r.reject_unknown({"canceled", "expires_at_ms"});
  return {r.required<bool>("canceled"), r.optional<int64_t>("expires_at_ms", 0)};
}

nlohmann::json ArtifactRegistration::to_json() const {
  return {{"lease_id", lease_id}, {"stage", stage}, {"name", name}, {"blob", blob}};
}

ArtifactRegistration ArtifactRegistration::from_json(const nlohmann::json& body,
                                                     const std::string& path) {
  FieldReader r(body, path);
  r.reject_unknown({"lease_id", "stage", "name", "blob"});
  ArtifactRegistration out{r.required<std::string>("lease_id"), r.required<std::string>("stage"),
                           r.required<std::string>("name"), r.required<std::string>("blob")};
  if (!is_sha256_hex(out.blob))
    throw ContractError(r.child("blob") + ": expected 64 lowercase hex digits");
  if (out.name.empty() || out.name.find('/') != std::string::npos ||
      out.name.find("..") != std::string::npos)
    throw ContractError(r.child("name") + ": expected a plain file name without '/' or '..'");
  return out;
}

nlohmann::json StageCompletion::to_json() const {
  return {{"lease_id", lease_id}, {"report", report}, {"seconds", seconds}};
}

StageCompletion StageCompletion::from_json(const nlohmann::json& body, const std::string& path) {
  FieldReader r(body, path);
  r.reject_unknown({"lease_id", "report", "seconds"});
  return {r.required<std::string>("lease_id"), object_field(r, "report"),
          r.optional<double>("seconds", 0.0)};
}

nlohmann::json JobFinish::to_json() const { return {{"lease_id", lease_id}, {"error", error}}; }

JobFinish JobFinish::from_json(const nlohmann::json& body, const std::string& path) {
  FieldReader r(body, path);
  r.reject_unknown({"lease_id", "error"});
  return {r.required<std::string>("lease_id"), r.optional<std::string>("error", "")};
}

nlohmann::json LogPage::to_json() const {
  nlohmann::json lines_json = nlohmann::json::array();
  for (const auto& line : lines)
    lines_json.push_back({{"seq", line.seq}, {"t_ms", line.t_ms}, {"text", line.text}});
  return {{"lines", lines_json}, {"next", next}};
}

LogPage LogPage::from_json(const nlohmann::json& body, const std::string& path) {
  FieldReader r(body, path);
  r.reject_unknown({"lines", "next"});
  LogPage page;
  page.next = r.required<int64_t>("next");
  const auto& lines = r.at("lines");
  if (!lines.is_array()) throw ContractError(r.child("lines") + ": expected array");
  for (size_t i = 0; i < lines.size(); ++i) {
    FieldReader line(lines[i], r.child("lines") + "[" + std::to_string(i) + "]");
    page.lines.push_back({line.required<int64_t>("seq"), line.optional<int64_t>("t_ms", 0),
                          line.required<std::string>("text")});
  }
  return page;
}

}  // namespace keel::proto
