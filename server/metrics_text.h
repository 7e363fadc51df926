// /metrics in the Prometheus text exposition format (version 0.0.4): a HELP and a TYPE
// line per metric family, then its samples.
#pragma once

#include <string>

#include "server/request_counters.h"
#include "storage/store.h"

namespace keel::server {

std::string render_metrics(const storage::Metrics& store_metrics, const RequestCounters& counters,
                           int workers_alive);

}  // namespace keel::server
