// keel: the Keel client CLI for a field laptop (docs/cli.md).
#include <CLI/CLI.hpp>

#include <cstdio>

#include "client/api_client.h"
#include "client/commands.h"
#include "client/exit_codes.h"
#include "client/local_file_error.h"
#include "proto/contract_error.h"

namespace {

using namespace keel::client;

int run(int argc, char** argv) {
  CLI::App app{"keel: submit inspection missions to a Keel server, follow jobs, fetch results"};
  app.footer(exit_code_help());
  app.require_subcommand(1);
  CliContext context;
  app.add_option("--url", context.flags.url,
                 "Server URL, http://host:port or https://host:port (env KEEL_URL)");
  app.add_option("--ca-file", context.flags.ca_file,
                 "https: PEM CA certificates to trust instead of the system's (env KEEL_CA_FILE)");
  app.add_option("--token", context.flags.token, "API token (env KEEL_TOKEN or KEEL_TOKEN_FILE)");
  app.add_option("--config", context.flags.config_file,
                 "Config file (default ~/.config/keel/config.yaml)");
  app.add_option("--timeout", context.timeout_s, "Seconds one request may take")
      ->check(CLI::PositiveNumber);
  app.add_flag("-v,--verbose", context.verbose, "Say which URL and token source are used");
  add_submit_command(app, context);
  add_job_commands(app, context);
  add_watch_commands(app, context);
  add_fetch_command(app, context);
  add_mission_commands(app, context);
  add_compare_command(app, context);
  add_init_command(app, context);

  try {
    app.parse(argc, argv);  // the chosen command runs in its callback
    return context.exit_code;
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? kExitOk : kExitUsage;
  } catch (const ApiCallError& e) {
    if (e.status() > 0) {
      std::fprintf(stderr, "keel: server refused (%d %s): %s\n", e.status(), e.code().c_str(),
                   e.what());
    } else {
      std::fprintf(stderr, "keel: %s: %s\n", e.code().c_str(), e.what());
    }
    return exit_code_for(e);
  } catch (const LocalFileError& e) {
    std::fprintf(stderr, "keel: %s\n", e.what());
    return kExitLocalFile;
  } catch (const keel::proto::ContractError& e) {
    std::fprintf(stderr, "keel: %s\n", e.what());
    return kExitUsage;
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "keel: %s\n", e.what());
    return kExitUsage;
  } catch (const std::filesystem::filesystem_error& e) {
    std::fprintf(stderr, "keel: %s\n", e.what());
    return kExitLocalFile;
  } catch (const std::runtime_error& e) {
    // File helpers (sha256_file, uploads) report local I/O trouble as runtime_error.
    std::fprintf(stderr, "keel: %s\n", e.what());
    return kExitLocalFile;
  }
}

}  // namespace

int main(int argc, char** argv) { return run(argc, argv); }
