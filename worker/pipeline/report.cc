#include "worker/pipeline/report.h"

#include <set>
#include <stdexcept>

#include "core/replaced_file.h"

namespace keel::pipeline {

nlohmann::ordered_json build_report(const ReportInput& input) {
  const std::set<std::string> in_order(input.stage_order.begin(), input.stage_order.end());
  if (!input.stages.is_object()) throw std::invalid_argument("report: stages must be an object");
  for (const auto& item : input.stages.items())
    if (!in_order.count(item.key()))
      throw std::invalid_argument("report: section '" + item.key() + "' is not a stage of the job");
  for (const auto& item : input.stage_seconds)
    if (!in_order.count(item.first))
      throw std::invalid_argument("report: stage_seconds." + item.first +
                                  " is not a stage of the job");

  nlohmann::ordered_json stages = nlohmann::ordered_json::object();
  nlohmann::ordered_json seconds = nlohmann::ordered_json::object();
  for (const auto& name : input.stage_order) {
    if (!input.stages.contains(name))
      throw std::invalid_argument("report: stage '" + name + "' has no section");
    const auto& section = input.stages.at(name);
    if (!section.is_object())
      throw std::invalid_argument("report: section of stage '" + name + "' is not an object");
    stages[name] = nlohmann::ordered_json(section);
    const auto it = input.stage_seconds.find(name);
    if (it != input.stage_seconds.end()) seconds[name] = it->second;
  }

  nlohmann::ordered_json report = nlohmann::ordered_json::object();
  report["keel_report"] = kReportVersion;
  report["job"] = nlohmann::ordered_json(input.job);
  report["mission"] = nlohmann::ordered_json(input.mission);
  if (!input.calibration.is_null())
    report["calibration"] = nlohmann::ordered_json(input.calibration);
  report["stages"] = std::move(stages);
  report["stage_seconds"] = std::move(seconds);
  if (!input.failure.is_null()) report["failed"] = nlohmann::ordered_json(input.failure);
  return report;
}

void write_json_atomically(const std::filesystem::path& path,
                           const nlohmann::ordered_json& document) {
  write_file_replacing(path, document.dump(2) + "\n");
}

}  // namespace keel::pipeline
