// State shared by every `keel` command: the global flags and a lazily made ApiClient.
#pragma once

#include <memory>
#include <string>

#include "client/api_client.h"
#include "client/cli_config.h"

namespace keel::client {

struct CliContext {
  CliFlags flags;
  bool verbose = false;
  double timeout_s = 60.0;
  int exit_code = 0;  // set by the command that ran

  // Resolves URL and token (flags > env > file) on first use and says where they came
  // from when verbose.
  ApiClient& api();
  const CliConfig& config();

 private:
  std::unique_ptr<CliConfig> config_;
  std::unique_ptr<ApiClient> client_;
};

// Cache folder for bundles and upload state: $XDG_CACHE_HOME/keel, else ~/.cache/keel.
std::string default_cache_dir(const EnvLookup& env = process_environment());

}  // namespace keel::client
