// URL and token sources: flags > environment > config file, with a temporary HOME.
#include "client/cli_config.h"

#include <gtest/gtest.h>

#include <map>

#include "client/cli_context.h"
#include "client/local_file_error.h"
#include "tests/temp_dir.h"

namespace keel::client {
namespace {

using keel::testing::TempDir;
using keel::testing::write_file;

struct FakeEnv {
  std::map<std::string, std::string> vars;
  EnvLookup lookup() const {
    return [this](const std::string& name) -> std::optional<std::string> {
      const auto it = vars.find(name);
      if (it == vars.end()) return std::nullopt;
      return it->second;
    };
  }
};

class CliConfigTest : public ::testing::Test {
 protected:
  void SetUp() override {
    env.vars["HOME"] = home.path().string();
    write_file(home.path() / ".config/keel/config.yaml",
               "url: http://file-host:7000\ntoken: file-token\n");
  }
  TempDir home;
  FakeEnv env;
};

TEST_F(CliConfigTest, ConfigFileAloneIsUsed) {
  const CliConfig config = resolve_cli_config({}, env.lookup());
  EXPECT_EQ(config.url, "http://file-host:7000");
  EXPECT_EQ(config.token, "file-token");
  EXPECT_EQ(config.url_source, (home.path() / ".config/keel/config.yaml").string());
}

TEST_F(CliConfigTest, EnvironmentBeatsFile) {
  env.vars["KEEL_URL"] = "http://env-host:7001";
  env.vars["KEEL_TOKEN"] = "env-token";
  const CliConfig config = resolve_cli_config({}, env.lookup());
  EXPECT_EQ(config.url, "http://env-host:7001");
  EXPECT_EQ(config.url_source, "KEEL_URL");
  EXPECT_EQ(config.token, "env-token");
  EXPECT_EQ(config.token_source, "KEEL_TOKEN");
}

TEST_F(CliConfigTest, FlagsBeatEnvironment) {
  env.vars["KEEL_URL"] = "http://env-host:7001";
  env.vars["KEEL_TOKEN"] = "env-token";
  CliFlags flags;
  flags.url = "http://flag-host:7002";
  flags.token = "flag-token";
  const CliConfig config = resolve_cli_config(flags, env.lookup());
  EXPECT_EQ(config.url, "http://flag-host:7002");
  EXPECT_EQ(config.url_source, "--url");
  EXPECT_EQ(config.token, "flag-token");
  EXPECT_EQ(config.token_source, "--token");
}

TEST_F(CliConfigTest, TokenFileFromEnvironmentBeatsFileToken) {
  write_file(home.path() / "token", "  tok-from-file \n");
  env.vars["KEEL_TOKEN_FILE"] = (home.path() / "token").string();
  const CliConfig config = resolve_cli_config({}, env.lookup());
  EXPECT_EQ(config.token, "tok-from-file");
  EXPECT_EQ(config.url, "http://file-host:7000");  // the URL still comes from the file
  // KEEL_TOKEN beats KEEL_TOKEN_FILE.
  env.vars["KEEL_TOKEN"] = "env-token";
  EXPECT_EQ(resolve_cli_config({}, env.lookup()).token, "env-token");
}

TEST_F(CliConfigTest, ExplicitConfigFileAndXdgConfigHome) {
  write_file(home.path() / "other.yaml", "url: http://other:1\ntoken_file: tok\n");
  write_file(home.path() / "tok", "relative-token\n");
  CliFlags flags;
  flags.config_file = (home.path() / "other.yaml").string();
  const CliConfig config = resolve_cli_config(flags, env.lookup());
  EXPECT_EQ(config.url, "http://other:1");
  EXPECT_EQ(config.token, "relative-token");

  write_file(home.path() / "xdg/keel/config.yaml", "url: http://xdg:2\n");
  env.vars["XDG_CONFIG_HOME"] = (home.path() / "xdg").string();
  EXPECT_EQ(resolve_cli_config({}, env.lookup()).url, "http://xdg:2");
}

TEST_F(CliConfigTest, NoFileNoEnvGivesDefaults) {
  std::filesystem::remove(home.path() / ".config/keel/config.yaml");
  const CliConfig config = resolve_cli_config({}, env.lookup());
  EXPECT_EQ(config.url, "http://127.0.0.1:8080");
  EXPECT_EQ(config.url_source, "default");
  EXPECT_EQ(config.token, "");
}

TEST_F(CliConfigTest, BadInputNamesTheFile) {
  CliFlags flags;
  flags.config_file = (home.path() / "missing.yaml").string();
  EXPECT_THROW(resolve_cli_config(flags, env.lookup()), LocalFileError);

  write_file(home.path() / ".config/keel/config.yaml", "url: http://h:1\ntokn: typo\n");
  try {
    resolve_cli_config({}, env.lookup());
    FAIL() << "expected LocalFileError";
  } catch (const LocalFileError& e) {
    EXPECT_NE(std::string(e.what()).find("config.yaml: unknown key 'tokn'"), std::string::npos)
        << e.what();
  }
  env.vars["KEEL_TOKEN_FILE"] = (home.path() / "nope").string();
  EXPECT_THROW(
      resolve_cli_config({}, FakeEnv{{{"KEEL_TOKEN_FILE", env.vars["KEEL_TOKEN_FILE"]}}}.lookup()),
      LocalFileError);
}

TEST(CliCacheDir, XdgCacheHomeThenHome) {
  FakeEnv env;
  env.vars["HOME"] = "/home/u";
  EXPECT_EQ(default_cache_dir(env.lookup()), "/home/u/.cache/keel");
  env.vars["XDG_CACHE_HOME"] = "/tmp/c";
  EXPECT_EQ(default_cache_dir(env.lookup()), "/tmp/c/keel");
}

}  // namespace
}  // namespace keel::client
