// The `keel` subcommands, one group per file; each registers itself on the app and stores
// its exit code in the context.
#pragma once

#include <CLI/CLI.hpp>

#include "client/cli_context.h"

namespace keel::client {

void add_submit_command(CLI::App& app, CliContext& context);    // commands_submit.cc
void add_job_commands(CLI::App& app, CliContext& context);      // jobs, status, cancel, retry
void add_watch_commands(CLI::App& app, CliContext& context);    // watch, log
void add_fetch_command(CLI::App& app, CliContext& context);     // fetch
void add_mission_commands(CLI::App& app, CliContext& context);  // missions, reprocess
void add_compare_command(CLI::App& app, CliContext& context);   // compare (issue 16)
void add_init_command(CLI::App& app, CliContext& context);      // init (commands_init.cc)

}  // namespace keel::client
