// The JSON contracts of the API and the worker protocol (proto/) that fuzz_json_contracts
// reads, by selector: its input's first byte picks the contract, the rest is the document.
// fuzz_seeds writes a valid document of each (contract_seeds.h), checked with this reader.
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <type_traits>
#include <utility>

#include "proto/api_error.h"
#include "proto/auth.h"
#include "proto/contract_error.h"
#include "proto/job.h"
#include "proto/mission_manifest.h"
#include "proto/resources.h"
#include "proto/worker_protocol.h"

namespace keel::fuzz {

template <typename T, typename = void>
struct HasToJson : std::false_type {};
template <typename T>
struct HasToJson<T, std::void_t<decltype(std::declval<const T&>().to_json())>> : std::true_type {};

// Reads `body` as T: false when refused (ContractError, its message in *refusal). What was read is
// written back, and that must read again (a ContractError there propagates: the fuzzer reports it).
template <typename T>
bool read_as(const nlohmann::json& body, std::string* refusal) {
  T value;
  try {
    value = T::from_json(body, "");
  } catch (const proto::ContractError& e) {
    if (refusal != nullptr) *refusal = e.what();
    return false;
  }
  if constexpr (HasToJson<T>::value) (void)T::from_json(value.to_json(), "");
  return true;
}

inline constexpr int kContracts = 24;

// Contract `selector` (0 .. kContracts - 1; its name with contract_name).
inline bool read_contract(int selector, const nlohmann::json& body,
                          std::string* refusal = nullptr) {
  namespace p = proto;
  switch (selector) {
    case 0:
      return read_as<p::ApiError>(body, refusal);
    case 1:
      return read_as<p::TokenInfo>(body, refusal);
    case 2:
      return read_as<p::TokenRequest>(body, refusal);
    case 3:
      return read_as<p::Project>(body, refusal);
    case 4:
      return read_as<p::JobRequest>(body, refusal);
    case 5:
      return read_as<p::Job>(body, refusal);
    case 6:
      return read_as<p::ComparisonRequest>(body, refusal);
    case 7:
      return read_as<p::ReprocessRequest>(body, refusal);
    case 8:
      return read_as<p::Batch>(body, refusal);
    case 9:
      return read_as<p::Upload>(body, refusal);
    case 10:
      return read_as<p::UploadRequest>(body, refusal);
    case 11:
      return read_as<p::Mission>(body, refusal);
    case 12:
      return read_as<p::MissionRequest>(body, refusal);
    case 13:
      return read_as<p::Artifact>(body, refusal);
    case 14:
      return read_as<p::LeaseRequest>(body, refusal);
    case 15:
      return read_as<p::Lease>(body, refusal);
    case 16:
      return read_as<p::Heartbeat>(body, refusal);
    case 17:
      return read_as<p::HeartbeatReply>(body, refusal);
    case 18:
      return read_as<p::ArtifactRegistration>(body, refusal);
    case 19:
      return read_as<p::StageCompletion>(body, refusal);
    case 20:
      return read_as<p::JobFinish>(body, refusal);
    case 21:
      return read_as<p::LogPage>(body, refusal);
    case 22:
      return read_as<p::MissionManifest>(body, refusal);
    case 23:
      return read_as<p::StageOutput>(body, refusal);
    default:
      return false;
  }
}

inline const char* contract_name(int selector) {
  static const char* const kNames[kContracts] = {
      "ApiError",
      "TokenInfo",
      "TokenRequest",
      "Project",
      "JobRequest",
      "Job",
      "ComparisonRequest",
      "ReprocessRequest",
      "Batch",
      "Upload",
      "UploadRequest",
      "Mission",
      "MissionRequest",
      "Artifact",
      "LeaseRequest",
      "Lease",
      "Heartbeat",
      "HeartbeatReply",
      "ArtifactRegistration",
      "StageCompletion",
      "JobFinish",
      "LogPage",
      "MissionManifest",
      "StageOutput",
  };
  return selector >= 0 && selector < kContracts ? kNames[selector] : "";
}

}  // namespace keel::fuzz
