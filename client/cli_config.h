// Where `keel` finds its server URL and token: flags > environment > config file.
//   flags:       --url, --token, --ca-file, --config (the config file's path)
//   environment: KEEL_URL, KEEL_TOKEN, KEEL_TOKEN_FILE (a file holding the token), KEEL_CA_FILE
//   file:        $XDG_CONFIG_HOME/keel/config.yaml or ~/.config/keel/config.yaml with
//                `url:`, `token:`, `token_file:` and/or `ca_file:`
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>

namespace keel::client {

struct CliFlags {
  std::string url;          // "" = not given
  std::string token;        // "" = not given
  std::string config_file;  // "" = the default path
  std::string ca_file;      // "" = not given
};

struct CliConfig {
  std::string url = "http://127.0.0.1:8080";
  std::string token;
  std::string url_source = "default";  // "--url", "KEEL_URL", "<file>", "default"
  std::string token_source = "none";   // "--token", "KEEL_TOKEN", "KEEL_TOKEN_FILE (<path>)", ...
  std::string ca_file;  // https: PEM CAs to trust instead of the system's ("" = system)
};

// Reads an environment variable; nullopt when unset. Tests substitute their own.
using EnvLookup = std::function<std::optional<std::string>(const std::string& name)>;
EnvLookup process_environment();

// The default config file: $XDG_CONFIG_HOME/keel/config.yaml, else $HOME/.config/keel/config.yaml.
std::filesystem::path default_config_file(const EnvLookup& env);

// Resolves URL and token. A config file named by --config must exist; the default one may
// be absent. Throws LocalFileError naming the file (unreadable token file, bad YAML,
// unknown key in the config file).
CliConfig resolve_cli_config(const CliFlags& flags, const EnvLookup& env = process_environment());

// The first line of a token file, surrounding whitespace removed.
std::string read_token_file(const std::filesystem::path& file);

}  // namespace keel::client
