// Building API answers: JSON bodies, the error body {"error": {"code", "message"}} and
// ApiException, which route code throws to answer with a specific status and code.
#pragma once

#include <nlohmann/json.hpp>

#include <stdexcept>
#include <string>

#include "server/http_types.h"

namespace keel::server {

// Thrown by route code; the handler turns it into the error response.
class ApiException : public std::runtime_error {
 public:
  ApiException(int status, std::string code, const std::string& message, Headers headers = {})
      : std::runtime_error(message),
        status_(status),
        code_(std::move(code)),
        headers_(std::move(headers)) {}
  int status() const { return status_; }
  const std::string& code() const { return code_; }
  const Headers& headers() const { return headers_; }

 private:
  int status_;
  std::string code_;
  Headers headers_;
};

Response json_response(int status, const nlohmann::json& body);
Response error_response(int status, const std::string& code, const std::string& message);
Response empty_response(int status);  // 204 and friends: no body

// Parses the request body as a JSON object; ApiException 400 `bad_json` otherwise.
nlohmann::json parse_json_body(const Request& request);

}  // namespace keel::server
