#include "client/job_format.h"

#include <algorithm>
#include <cstdio>
#include <ctime>

namespace keel::client {

namespace {

std::string join(const std::vector<std::string>& items, const char* separator) {
  std::string out;
  for (const auto& item : items) out += (out.empty() ? "" : separator) + item;
  return out;
}

std::string percent(double fraction) {
  char text[16];
  std::snprintf(text, sizeof(text), "%.0f%%", 100.0 * std::clamp(fraction, 0.0, 1.0));
  return text;
}

std::string seconds_text(double seconds) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.1f s", seconds);
  return text;
}

std::string short_sha(const std::string& sha) { return sha.size() > 12 ? sha.substr(0, 12) : sha; }

}  // namespace

std::string format_time_ms(int64_t t_ms) {
  if (t_ms <= 0) return "-";
  const std::time_t seconds = static_cast<std::time_t>(t_ms / 1000);
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char text[32];
  std::strftime(text, sizeof(text), "%Y-%m-%d %H:%M:%SZ", &utc);
  return text;
}

std::string format_table(const std::vector<std::vector<std::string>>& rows) {
  std::vector<size_t> widths;
  for (const auto& row : rows)
    for (size_t c = 0; c < row.size(); ++c) {
      if (widths.size() <= c) widths.push_back(0);
      widths[c] = std::max(widths[c], row[c].size());
    }
  std::string out;
  for (const auto& row : rows) {
    std::string line;
    for (size_t c = 0; c < row.size(); ++c) {
      line += row[c];
      if (c + 1 < row.size()) line += std::string(widths[c] - row[c].size() + 2, ' ');
    }
    out += line + "\n";
  }
  return out;
}

std::string format_job_table(const std::vector<proto::Job>& jobs) {
  std::vector<std::vector<std::string>> rows = {
      {"ID", "STATE", "STAGE", "PROGRESS", "MISSION", "CREATED"}};
  for (const auto& job : jobs) {
    const bool running = job.state == proto::JobState::kRunning;
    rows.push_back({job.id, proto::to_string(job.state), job.stage.empty() ? "-" : job.stage,
                    running ? percent(job.progress) : "-", job.mission_id,
                    format_time_ms(job.created_at_ms)});
  }
  return format_table(rows);
}

std::string format_mission_table(const std::vector<proto::Mission>& missions) {
  std::vector<std::vector<std::string>> rows = {{"ID", "NAME", "BUNDLE", "CAD", "CREATED"}};
  for (const auto& m : missions)
    rows.push_back({m.id, m.name, short_sha(m.bundle_blob), m.cad_name.empty() ? "-" : m.cad_name,
                    format_time_ms(m.created_at_ms)});
  return format_table(rows);
}

std::string format_job_status(const proto::Job& job) {
  std::string out = "job:       " + job.id + "\n";
  out += "mission:   " + job.mission_id + "\n";
  out += "state:     " + proto::to_string(job.state);
  if (job.state == proto::JobState::kRunning && !job.stage.empty())
    out += " (" + job.stage + " " + percent(job.progress) + ")";
  out += "\n";
  out += "stages:    " + join(job.stages, ", ") + "\n";
  out += "completed: " + (job.completed_stages.empty() ? "-" : join(job.completed_stages, ", ")) +
         "\n";
  for (const auto& [stage, seconds] : job.stage_seconds)
    out += "  " + stage + ": " + seconds_text(seconds) + "\n";
  if (!job.options.empty()) out += "options:   " + job.options.dump() + "\n";
  out += "attempts:  " + std::to_string(job.attempts) + "\n";
  out += "created:   " + format_time_ms(job.created_at_ms) + "\n";
  out += "started:   " + format_time_ms(job.started_at_ms) + "\n";
  out += "finished:  " + format_time_ms(job.finished_at_ms) + "\n";
  if (!job.error.empty()) out += "error:     " + job.error + "\n";
  return out;
}

}  // namespace keel::client
