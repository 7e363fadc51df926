#include "client/cli_context.h"

#include <cstdio>
#include <filesystem>

namespace keel::client {

const CliConfig& CliContext::config() {
  if (!config_) {
    config_ = std::make_unique<CliConfig>(resolve_cli_config(flags));
    if (verbose) {
      std::fprintf(stderr, "keel: server %s (from %s)\n", config_->url.c_str(),
                   config_->url_source.c_str());
      std::fprintf(stderr, "keel: token from %s\n", config_->token_source.c_str());
    }
  }
  return *config_;
}

ApiClient& CliContext::api() {
  if (!client_) {
    ClientConfig client_config;
    client_config.url = config().url;
    client_config.token = config().token;
    client_config.ca_file = config().ca_file;
    client_config.timeout_s = timeout_s;
    client_ = std::make_unique<ApiClient>(client_config);
  }
  return *client_;
}

std::string default_cache_dir(const EnvLookup& env) {
  if (const auto xdg = env("XDG_CACHE_HOME"); xdg && !xdg->empty())
    return (std::filesystem::path(*xdg) / "keel").string();
  const auto home = env("HOME");
  return (std::filesystem::path(home ? *home : ".") / ".cache" / "keel").string();
}

}  // namespace keel::client
