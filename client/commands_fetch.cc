// keel fetch <job> [--artifact NAME]... -o DIR: downloads artifacts with Range resume and a
// SHA-256 check, prints the paths.
#include <algorithm>
#include <cstdio>
#include <memory>

#include "client/commands.h"
#include "client/http_url.h"
#include "client/progress_bar.h"

namespace keel::client {

namespace fs = std::filesystem;

namespace {

struct FetchArgs {
  std::string job_id;
  std::vector<std::string> names;
  std::string out_dir;
  bool quiet = false;
};

// Artifact names come from the server: only plain file names may become local paths.
void check_safe_name(const std::string& name) {
  if (name.empty() || name == "." || name == ".." || name.find('/') != std::string::npos ||
      name.find('\\') != std::string::npos)
    throw ApiCallError(0, "bad_response", "artifact name '" + name + "' is not a plain file name");
}

std::vector<proto::Artifact> select(const std::vector<proto::Artifact>& all,
                                    const std::vector<std::string>& names, const std::string& job) {
  if (names.empty()) return all;
  std::vector<proto::Artifact> out;
  for (const auto& name : names) {
    const auto it =
        std::find_if(all.begin(), all.end(), [&](const auto& a) { return a.name == name; });
    if (it == all.end()) {
      std::string known;
      for (const auto& a : all) known += (known.empty() ? "" : ", ") + a.name;
      throw ApiCallError(404, "not_found",
                         "job " + job + " has no artifact '" + name +
                             "' (it has: " + (known.empty() ? "none" : known) + ")");
    }
    out.push_back(*it);
  }
  return out;
}

int run_fetch(CliContext& context, const FetchArgs& args) {
  ApiClient& api = context.api();
  const auto artifacts = select(api.list_artifacts(args.job_id), args.names, args.job_id);
  ProgressBarOptions bar_options;
  bar_options.terminal = is_terminal(stderr);
  for (const proto::Artifact& artifact : artifacts) {
    check_safe_name(artifact.name);
    const fs::path destination = fs::path(args.out_dir) / artifact.name;
    ProgressBar bar(artifact.name, bar_options);
    ProgressFn progress;
    if (!args.quiet)
      progress = [&](int64_t done, int64_t total) { bar.update(done, total, monotonic_seconds()); };
    api.download("/v1/artifacts/" + url_encode(artifact.id), destination, artifact.sha256,
                 progress);
    if (!args.quiet) bar.finish(monotonic_seconds());
    std::printf("%s\n", destination.string().c_str());
    std::fflush(stdout);
  }
  return 0;
}

}  // namespace

void add_fetch_command(CLI::App& app, CliContext& context) {
  auto args = std::make_shared<FetchArgs>();
  CLI::App* cmd =
      app.add_subcommand("fetch", "Download a job's artifacts (resumable, SHA-256 checked)");
  cmd->add_option("job", args->job_id, "Job id")->required();
  cmd->add_option("--artifact", args->names, "Artifact name to fetch (repeatable; default: all)");
  cmd->add_option("-o,--output", args->out_dir, "Folder to write the artifacts into")->required();
  cmd->add_flag("-q,--quiet", args->quiet, "No progress output on stderr");
  cmd->callback([&context, args] { context.exit_code = run_fetch(context, *args); });
}

}  // namespace keel::client
