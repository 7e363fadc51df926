// `keel-worker options`: every stage's options with their defaults (JSON), their docs tables
// (`--markdown`), or docs/stage-options.md brought up to date (`--docs FILE`; with `--check`,
// exit 1 naming the stages whose tables the file has out of date).
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>

#include "worker/main/commands.h"
#include "worker/pipeline/option_docs.h"
#include "worker/pipeline/option_table.h"
#include "worker/pipeline/stage.h"

namespace keel::worker {

namespace {

struct OptionsArgs {
  std::string stage;
  bool markdown = false;
  std::string docs;
  bool check = false;
};

int run_options(const OptionsArgs& args) {
  std::vector<std::string> stages = pipeline::available_stages();
  if (!args.stage.empty()) stages = {args.stage};
  if (!args.docs.empty()) {
    std::ifstream in(args.docs);
    if (!in) {
      std::cerr << "keel-worker options: cannot read " << args.docs << "\n";
      return kExitUsage;
    }
    std::stringstream text;
    text << in.rdbuf();
    std::vector<std::string> stale;
    const std::string updated = pipeline::update_option_docs(text.str(), &stale);
    if (args.check) {
      for (const auto& stage : stale)
        std::cerr << args.docs << ": the options of stage '" << stage
                  << "' are out of date (keel-worker options --docs " << args.docs << ")\n";
      return stale.empty() ? kExitOk : kExitStageFailed;
    }
    std::ofstream(args.docs) << updated;
    return kExitOk;
  }
  try {
    nlohmann::ordered_json all = nlohmann::ordered_json::object();
    for (const auto& stage : stages) {
      const auto made = pipeline::make_stage(stage);
      if (args.markdown)
        std::cout << "## `" << stage << "`\n\n" << made->options().markdown() << "\n";
      else
        all[stage] = made->options().defaults();
    }
    if (!args.markdown) std::cout << all.dump(2) << "\n";
  } catch (const std::exception& e) {
    std::cerr << "keel-worker options: " << e.what() << "\n";
    return kExitUsage;
  }
  return kExitOk;
}

}  // namespace

Subcommand add_options_command(CLI::App& app) {
  auto args = std::make_shared<OptionsArgs>();
  CLI::App* cmd = app.add_subcommand("options", "Every stage's options, defaults and docs");
  cmd->add_option("--stage", args->stage, "Only this stage");
  cmd->add_flag("--markdown", args->markdown, "The docs' tables instead of the defaults as JSON");
  cmd->add_option("--docs", args->docs, "Rewrite the option tables of this Markdown file");
  cmd->add_flag("--check", args->check, "With --docs: exit 2 if the file's tables are stale");
  return {cmd, [args] { return run_options(*args); }};
}

}  // namespace keel::worker
