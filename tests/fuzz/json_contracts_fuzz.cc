// Every JSON contract of the API and the worker protocol (proto/): any document either
// reads into the struct or is refused with a ContractError naming the field.
#include <nlohmann/json.hpp>

#include <type_traits>
#include <utility>

#include "proto/api_error.h"
#include "proto/auth.h"
#include "proto/contract_error.h"
#include "proto/job.h"
#include "proto/mission_manifest.h"
#include "proto/resources.h"
#include "proto/worker_protocol.h"
#include "tests/fuzz/fuzz_util.h"

namespace {

template <typename T, typename = void>
struct HasToJson : std::false_type {};
template <typename T>
struct HasToJson<T, std::void_t<decltype(std::declval<const T&>().to_json())>> : std::true_type {};

template <typename T>
void read_as(const nlohmann::json& body) {
  T value;
  try {
    value = T::from_json(body, "");
  } catch (const keel::proto::ContractError&) {
    return;
  }
  // What was read is written back, and that must read again (no ContractError allowed).
  if constexpr (HasToJson<T>::value) (void)T::from_json(value.to_json(), "");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  namespace p = keel::proto;
  const auto input = keel::fuzz::split_selector(data, size);
  const nlohmann::json body = nlohmann::json::parse(input.data, input.data + input.size, nullptr,
                                                    /*allow_exceptions=*/false);
  if (body.is_discarded()) return 0;
  switch (input.selector % 24) {
    case 0:
      read_as<p::ApiError>(body);
      break;
    case 1:
      read_as<p::TokenInfo>(body);
      break;
    case 2:
      read_as<p::TokenRequest>(body);
      break;
    case 3:
      read_as<p::Project>(body);
      break;
    case 4:
      read_as<p::JobRequest>(body);
      break;
    case 5:
      read_as<p::Job>(body);
      break;
    case 6:
      read_as<p::ComparisonRequest>(body);
      break;
    case 7:
      read_as<p::ReprocessRequest>(body);
      break;
    case 8:
      read_as<p::Batch>(body);
      break;
    case 9:
      read_as<p::Upload>(body);
      break;
    case 10:
      read_as<p::UploadRequest>(body);
      break;
    case 11:
      read_as<p::Mission>(body);
      break;
    case 12:
      read_as<p::MissionRequest>(body);
      break;
    case 13:
      read_as<p::Artifact>(body);
      break;
    case 14:
      read_as<p::LeaseRequest>(body);
      break;
    case 15:
      read_as<p::Lease>(body);
      break;
    case 16:
      read_as<p::Heartbeat>(body);
      break;
    case 17:
      read_as<p::HeartbeatReply>(body);
      break;
    case 18:
      read_as<p::ArtifactRegistration>(body);
      break;
    case 19:
      read_as<p::StageCompletion>(body);
      break;
    case 20:
      read_as<p::JobFinish>(body);
      break;
    case 21:
      read_as<p::LogPage>(body);
      break;
    case 22:
      read_as<p::MissionManifest>(body);
      break;
    default:
      read_as<p::StageOutput>(body);
      break;
  }
  return 0;
}
