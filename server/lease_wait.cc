#include "server/lease_wait.h"

#include "server/api_response.h"

namespace keel::server {

std::optional<Response> try_lease(storage::Store& store, const proto::LeaseRequest& request) {
  // The store's lease is complete: a compare job's jobs A and B come with it.
  std::optional<proto::Lease> lease = store.lease_job(request);
  if (!lease) return std::nullopt;
  return json_response(200, lease->to_json());
}

LeaseWait::LeaseWait(storage::Store& store, proto::LeaseRequest request,
                     std::chrono::steady_clock::time_point deadline)
    : store_(store), request_(std::move(request)), deadline_(deadline) {}

LeaseWait::~LeaseWait() { subscription_.reset(); }

void LeaseWait::start(std::function<void()> wake) {
  const proto::TokenInfo scope{"", "", proto::Role::kWorker,
                               request_.project.empty() ? proto::kAllProjects : request_.project};
  subscription_ = store_.subscribe([wake, scope](const storage::Change& change) {
    if (change.kind == storage::Change::Kind::kJob &&
        change.state == proto::JobState::kQueued && scope.reaches(change.project))
      wake();
  });
  wake();  // a job queued before the subscription started is found by this first try
}

std::optional<Response> LeaseWait::poll(bool final) {
  if (auto answer = try_lease(store_, request_)) return answer;
  if (final) return empty_response(204);
  return std::nullopt;
}

}  // namespace keel::server
