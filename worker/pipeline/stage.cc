#include "worker/pipeline/stage.h"

#include <map>
#include <memory>
#include <mutex>

#include "worker/pipeline/option_table.h"

namespace keel::pipeline {

namespace {
struct NoOptions {};
}  // namespace

// A stage without options accepts only {} (its table has no rows).
const OptionsSchema& Stage::options() const {
  static std::mutex mutex;
  static std::map<std::string, std::unique_ptr<OptionTable<NoOptions>>> tables;
  const std::lock_guard<std::mutex> lock(mutex);
  auto& table = tables[name()];
  if (!table) table = std::make_unique<OptionTable<NoOptions>>(name(), OptionTable<NoOptions>::Rows{});
  return *table;
}

}  // namespace keel::pipeline
