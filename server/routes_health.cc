// GET /healthz and GET /metrics: open, no token.
#include "server/api_response.h"
#include "server/metrics_text.h"
#include "server/routes.h"

namespace keel::server::routes {

Response healthz(const Call& call) {
  return json_response(200, {{"status", "ok"}, {"version", call.options.version}});
}

Response metrics(const Call& call) {
  int workers = call.options.workers_alive ? call.options.workers_alive() : 0;
  Response response;
  response.status = 200;
  response.headers.set("Content-Type", "text/plain; version=0.0.4; charset=utf-8");
  response.body = render_metrics(call.store.metrics(), call.counters, workers);
  return response;
}

}  // namespace keel::server::routes
