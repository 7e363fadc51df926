#include "proto/options.h"

#include <algorithm>

#include "proto/calibration.h"
#include "proto/contract_error.h"
#include "proto/stages.h"

namespace keel::proto {

const std::vector<std::string>& known_stages() {
#define KEEL_STAGE_NAME(name) #name,
  static const std::vector<std::string> stages = {KEEL_STAGES(KEEL_STAGE_NAME)};
#undef KEEL_STAGE_NAME
  return stages;
}

bool is_known_stage(std::string_view stage) {
  const auto& stages = known_stages();
  return std::find(stages.begin(), stages.end(), stage) != stages.end();
}

static std::string known_list() {
  std::string out;
  for (const auto& s : known_stages()) out += (out.empty() ? "" : ", ") + s;
  return out;
}

std::vector<std::string> parse_stage_list(std::string_view text) {
  std::vector<std::string> stages;
  size_t start = 0;
  while (start <= text.size()) {
    size_t comma = text.find(',', start);
    if (comma == std::string_view::npos) comma = text.size();
    std::string name(text.substr(start, comma - start));
    if (!name.empty()) stages.push_back(name);
    start = comma + 1;
  }
  validate_stage_list(stages, "stages");
  return stages;
}

void validate_stage_list(const std::vector<std::string>& stages, const std::string& path) {
  if (stages.empty()) throw ContractError(path + ": expected at least one stage");
  for (size_t i = 0; i < stages.size(); ++i) {
    const std::string item = path + "[" + std::to_string(i) + "]";
    if (!is_known_stage(stages[i]))
      throw ContractError(item + ": unknown stage '" + stages[i] + "' (known: " + known_list() +
                          ")");
    for (size_t j = 0; j < i; ++j)
      if (stages[j] == stages[i])
        throw ContractError(item + ": stage '" + stages[i] + "' repeated");
  }
}

namespace {

// "calibration.<sensor>.<key>=<pose>" replaces the sensor's override (one key per sensor);
// "calibration.<sensor>=<object>" sets it whole. Checked at once, so `--set` fails early.
void apply_calibration_assignment(nlohmann::json& options, std::string_view assignment) {
  const size_t eq = assignment.find('=');
  const std::string key(assignment.substr(0, eq));
  const std::string where = "option '" + std::string(assignment) + "'";
  const std::string rest = key.substr(std::string(kCalibrationOption).size() + 1);
  const size_t dot = rest.find('.');
  const std::string sensor = rest.substr(0, dot);
  const std::string field = dot == std::string::npos ? "" : rest.substr(dot + 1);
  if (sensor.empty() ||
      (dot != std::string::npos && (field.empty() || field.find('.') != std::string::npos)))
    throw ContractError(where +
                        ": expected calibration.<sensor>.T_body_sensor=<pose> or "
                        "calibration.<sensor>.T_<reference>_<sensor>=<pose>");
  const std::string text(assignment.substr(eq + 1));
  const nlohmann::json value = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (value.is_discarded())
    throw ContractError(key +
                        ": expected a JSON pose {\"xyz_m\": [x, y, z], \"rpy_deg\": "
                        "[roll, pitch, yaw]}, got '" +
                        text + "'");
  if (!options.is_object()) options = nlohmann::json::object();
  nlohmann::json calibration = options.value(kCalibrationOption, nlohmann::json::object());
  if (!calibration.is_object()) calibration = nlohmann::json::object();
  calibration[sensor] = field.empty() ? value : nlohmann::json{{field, value}};
  parse_calibration(nlohmann::json{{sensor, calibration[sensor]}});
  options[kCalibrationOption] = std::move(calibration);
}

}  // namespace

void apply_option_assignment(nlohmann::json& options, std::string_view assignment) {
  const size_t eq = assignment.find('=');
  const std::string where = "option '" + std::string(assignment) + "'";
  if (eq == std::string_view::npos) throw ContractError(where + ": expected stage.option=value");
  const std::string_view key = assignment.substr(0, eq);
  const size_t dot = key.find('.');
  if (dot == std::string_view::npos || dot == 0 || dot + 1 == key.size())
    throw ContractError(where + ": expected stage.option=value");
  const std::string stage(key.substr(0, dot));
  const std::string option(key.substr(dot + 1));
  if (stage == kCalibrationOption) return apply_calibration_assignment(options, assignment);
  if (!is_known_stage(stage))
    throw ContractError(where + ": unknown stage '" + stage + "' (known: " + known_list() + ")");
  const std::string text(assignment.substr(eq + 1));
  nlohmann::json value = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (value.is_discarded()) value = text;
  if (!options.is_object()) options = nlohmann::json::object();
  options[stage][option] = value;
}

void validate_options(const nlohmann::json& options, const std::string& path) {
  if (options.is_null()) return;
  if (!options.is_object())
    throw ContractError(path + ": expected object, got " + json_type_name(options));
  for (const auto& item : options.items()) {
    const std::string child = path + "." + item.key();
    if (item.key() == kCalibrationOption) {
      parse_calibration(item.value(), child);
      continue;
    }
    if (!is_known_stage(item.key()))
      throw ContractError(child + ": unknown stage (known: " + known_list() + ")");
    if (!item.value().is_object())
      throw ContractError(child + ": expected object of options, got " +
                          json_type_name(item.value()));
  }
}

}  // namespace keel::proto
