// GET / and the dashboard's static files (web/): no token, like /healthz. The page then
// calls /v1/* with the bearer token the user signs in with.
#include "server/api_response.h"
#include "server/routes.h"
#include "server/static_files.h"

namespace keel::server::routes {

Response web_file(const Call& call) {
  if (!call.options.web)
    throw ApiException(404, "not_found",
                       "no route " + call.request.method + " " + call.target.path +
                           " (this server runs without the web dashboard)");
  return call.options.web->serve(call.request, call.target.segments);
}

}  // namespace keel::server::routes
