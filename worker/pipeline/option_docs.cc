#include "worker/pipeline/option_docs.h"

#include "worker/pipeline/option_table.h"
#include "worker/pipeline/stage.h"

namespace keel::pipeline {

std::string update_option_docs(const std::string& document, std::vector<std::string>* stale) {
  std::string out = document;
  for (const auto& stage : available_stages()) {
    const std::string begin = "<!-- options: " + stage + " -->\n";
    const std::string end = "<!-- /options: " + stage + " -->";
    const size_t from = out.find(begin);
    if (from == std::string::npos) continue;
    const size_t inner = from + begin.size();
    const size_t to = out.find(end, inner);
    if (to == std::string::npos) continue;
    const std::string tables = make_stage(stage)->options().markdown();
    if (out.compare(inner, to - inner, tables) != 0 && stale) stale->push_back(stage);
    out.replace(inner, to - inner, tables);
  }
  return out;
}

}  // namespace keel::pipeline
