// Making API tokens, shared by the admin API (POST /v1/tokens) and `keel-server token
// create`: a random token (data_dir.h random_token) stored hashed with its role, project
// and expiry. The clear token exists only in the answer.
#pragma once

#include <cstdint>
#include <string>

#include "proto/auth.h"
#include "storage/store.h"

namespace keel::server {

struct IssuedToken {
  std::string token;  // the clear token: shown once, never stored
  proto::TokenInfo info;
};

// Makes and stores a token per `request`; an expiry counts from `now_ms`.
IssuedToken issue_token(storage::Store& store, const proto::TokenRequest& request, int64_t now_ms);

// A duration as people write it: "90s", "45m", "12h", "30d", "2w" or plain seconds; "0" or
// "never" = no expiry (0). std::invalid_argument naming the text otherwise.
int64_t parse_duration_seconds(const std::string& text);

}  // namespace keel::server
