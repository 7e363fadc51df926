#include "client/cli_config.h"

#include <yaml-cpp/yaml.h>

#include <cstdlib>
#include <fstream>

#include "client/local_file_error.h"

namespace keel::client {

namespace fs = std::filesystem;

namespace {

std::string trim(const std::string& text) {
  const auto begin = text.find_first_not_of(" \t\r\n");
  if (begin == std::string::npos) return "";
  const auto end = text.find_last_not_of(" \t\r\n");
  return text.substr(begin, end - begin + 1);
}

struct FileSettings {
  std::optional<std::string> url;
  std::optional<std::string> token;
  std::optional<std::string> token_file;
  std::optional<std::string> ca_file;
};

std::optional<std::string> string_key(const YAML::Node& root, const char* key,
                                      const fs::path& file) {
  const YAML::Node node = root[key];
  if (!node) return std::nullopt;
  if (!node.IsScalar()) throw LocalFileError(file.string() + ": " + key + ": expected a string");
  return node.as<std::string>();
}

FileSettings read_config_file(const fs::path& file) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(file.string());
  } catch (const YAML::Exception& e) {
    throw LocalFileError(file.string() + ": " + e.what());
  }
  FileSettings out;
  if (root.IsNull()) return out;
  if (!root.IsMap())
    throw LocalFileError(file.string() + ": expected a map of url/token/token_file/ca_file");
  for (const auto& item : root) {
    const std::string key = item.first.as<std::string>();
    if (key != "url" && key != "token" && key != "token_file" && key != "ca_file")
      throw LocalFileError(file.string() + ": unknown key '" + key +
                           "' (known: url, token, token_file, ca_file)");
  }
  out.url = string_key(root, "url", file);
  out.token = string_key(root, "token", file);
  out.token_file = string_key(root, "token_file", file);
  out.ca_file = string_key(root, "ca_file", file);
  return out;
}

// A relative token_file in the config file is relative to the config file's folder.
fs::path relative_to(const fs::path& file, const fs::path& base_file) {
  return file.is_absolute() ? file : base_file.parent_path() / file;
}

}  // namespace

EnvLookup process_environment() {
  return [](const std::string& name) -> std::optional<std::string> {
    const char* value = std::getenv(name.c_str());
    if (value == nullptr) return std::nullopt;
    return std::string(value);
  };
}

fs::path default_config_file(const EnvLookup& env) {
  if (const auto xdg = env("XDG_CONFIG_HOME"); xdg && !xdg->empty())
    return fs::path(*xdg) / "keel" / "config.yaml";
  const auto home = env("HOME");
  return fs::path(home ? *home : ".") / ".config" / "keel" / "config.yaml";
}

std::string read_token_file(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw LocalFileError(file.string() + ": cannot read token file");
  std::string line;
  std::getline(in, line);
  const std::string token = trim(line);
  if (token.empty()) throw LocalFileError(file.string() + ": token file is empty");
  return token;
}

CliConfig resolve_cli_config(const CliFlags& flags, const EnvLookup& env) {
  const fs::path config_file =
      flags.config_file.empty() ? default_config_file(env) : fs::path(flags.config_file);
  std::error_code ec;
  FileSettings file;
  if (fs::exists(config_file, ec)) {
    file = read_config_file(config_file);
  } else if (!flags.config_file.empty()) {
    throw LocalFileError(config_file.string() + ": config file not found");
  }

  CliConfig out;
  const auto env_url = env("KEEL_URL");
  const auto env_token = env("KEEL_TOKEN");
  const auto env_token_file = env("KEEL_TOKEN_FILE");
  if (!flags.url.empty()) {
    out.url = flags.url, out.url_source = "--url";
  } else if (env_url && !env_url->empty()) {
    out.url = *env_url, out.url_source = "KEEL_URL";
  } else if (file.url) {
    out.url = *file.url, out.url_source = config_file.string();
  }

  if (!flags.token.empty()) {
    out.token = flags.token, out.token_source = "--token";
  } else if (env_token && !env_token->empty()) {
    out.token = *env_token, out.token_source = "KEEL_TOKEN";
  } else if (env_token_file && !env_token_file->empty()) {
    out.token = read_token_file(*env_token_file);
    out.token_source = "KEEL_TOKEN_FILE (" + *env_token_file + ")";
  } else if (file.token) {
    out.token = *file.token, out.token_source = config_file.string();
  } else if (file.token_file) {
    const fs::path token_file = relative_to(*file.token_file, config_file);
    out.token = read_token_file(token_file);
    out.token_source = config_file.string() + " token_file (" + token_file.string() + ")";
  }

  const auto env_ca_file = env("KEEL_CA_FILE");
  if (!flags.ca_file.empty())
    out.ca_file = flags.ca_file;
  else if (env_ca_file && !env_ca_file->empty())
    out.ca_file = *env_ca_file;
  else if (file.ca_file)
    out.ca_file = relative_to(*file.ca_file, config_file).string();
  return out;
}

}  // namespace keel::client
