#include "server/api_response.h"

#include "proto/api_error.h"

namespace keel::server {

Response json_response(int status, const nlohmann::json& body) {
  Response response;
  response.status = status;
  response.headers.set("Content-Type", "application/json");
  response.body = body.dump();
  return response;
}

Response error_response(int status, const std::string& code, const std::string& message) {
  return json_response(status, proto::ApiError{code, message}.to_json());
}

Response empty_response(int status) {
  Response response;
  response.status = status;
  return response;
}

nlohmann::json parse_json_body(const Request& request) {
  if (request.body.empty())
    throw ApiException(400, "bad_json", "request body: expected a JSON object, got nothing");
  nlohmann::json body;
  try {
    body = nlohmann::json::parse(request.body);
  } catch (const nlohmann::json::parse_error& e) {
    // e.byte names the position; the message of nlohmann says what was expected there.
    throw ApiException(400, "bad_json", std::string("request body: not valid JSON: ") + e.what());
  }
  if (!body.is_object())
    throw ApiException(400, "bad_json", "request body: expected a JSON object");
  return body;
}

}  // namespace keel::server
