// docs/stage-options.md's option tables, made from the stages' option tables: each stage's
// block sits between `<!-- options: <stage> -->` and `<!-- /options: <stage> -->`, and the
// prose around the blocks is the docs' own.
#pragma once

#include <string>
#include <vector>

namespace keel::pipeline {

// `document` with every stage's block replaced by the stage's tables now (a block the
// document lacks is not added). `stale`, when given, receives the stages whose block changed.
std::string update_option_docs(const std::string& document,
                               std::vector<std::string>* stale = nullptr);

}  // namespace keel::pipeline
