#include "worker/ba/ba_options.h"

#include <stdexcept>

namespace keel::ba {

const char* to_string(BaMode mode) {
  switch (mode) {
    case BaMode::kNaive:
      return "naive";
    case BaMode::kGeva:
      return "geva";
    case BaMode::kProposed:
      return "proposed";
  }
  return "unknown";
}

BaMode ba_mode_from_string(const std::string& name) {
  if (name == "naive") return BaMode::kNaive;
  if (name == "geva") return BaMode::kGeva;
  if (name == "proposed") return BaMode::kProposed;
  throw std::invalid_argument("ba mode: expected naive, geva or proposed, got '" + name + "'");
}

}  // namespace keel::ba
