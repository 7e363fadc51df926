// Internal to client/: ApiClient's connection and the helpers its .cc files share.
#pragma once

#include <map>
#include <string>

#include "client/api_client.h"
#include "client/http_connection.h"

namespace keel::client {

struct ApiClient::Connection : HttpConnection {
  Connection(BaseUrl url, double timeout_s, TransferStats& stats, std::string token,
             const std::string& ca_file)
      : HttpConnection(std::move(url), timeout_s, stats, ca_file), token(std::move(token)) {}

  // Host, User-Agent, Authorization: Bearer, then the caller's headers.
  void prepare(http::fields& fields, const std::map<std::string, std::string>& headers) const;
  // Target with the URL's path prefix.
  std::string target(const std::string& path) const { return url().path_prefix + path; }

  std::string token;
};

// The ApiCallError of a non-2xx answer: the server's {"error": {code, message}} when the
// body has one, otherwise "http_<status>" and the start of the body.
ApiCallError error_from_answer(const HttpResult& result, const std::string& what);
// Parses a JSON answer (null for 204 / empty); throws ApiCallError(0, "bad_response").
nlohmann::json parse_json_body(const HttpResult& result, const std::string& what);

}  // namespace keel::client
