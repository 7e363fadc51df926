#include "worker/pipeline/report.h"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <set>
#include <stdexcept>


namespace keel::pipeline {

namespace {

std::runtime_error io_error(const std::filesystem::path& path, const std::string& what) {
  return std::runtime_error(path.string() + ": " + what + ": " + std::strerror(errno));
}

void write_all(int fd, const std::string& bytes, const std::filesystem::path& path) {
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw io_error(path, "write failed");
    done += static_cast<size_t>(n);
  }
}

}  // namespace

// A temporary file in the same folder, flushed, renamed over `path`.
void write_text_atomically(const std::filesystem::path& path, const std::string& text) {
  static std::atomic<unsigned> counter{0};
  const std::filesystem::path temp =
      path.string() + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter++);
  const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw io_error(temp, "cannot create");
  try {
    write_all(fd, text, temp);
    if (::fsync(fd) != 0) throw io_error(temp, "fsync failed");
  } catch (...) {
    ::close(fd);
    ::unlink(temp.c_str());
    throw;
  }
  if (::close(fd) != 0) {
    ::unlink(temp.c_str());
    throw io_error(temp, "close failed");
  }
  if (::rename(temp.c_str(), path.c_str()) != 0) {
    const auto error = io_error(path, "cannot rename " + temp.filename().string() + " over it");
    ::unlink(temp.c_str());
    throw error;
  }
}


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
  report["stages"] = std::move(stages);
  report["stage_seconds"] = std::move(seconds);
  if (!input.failure.is_null()) report["failed"] = nlohmann::ordered_json(input.failure);
  return report;
}

void write_json_atomically(const std::filesystem::path& path,
                           const nlohmann::ordered_json& document) {
  write_text_atomically(path, document.dump(2) + "\n");
}

}  // namespace keel::pipeline
