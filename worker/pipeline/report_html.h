// report.html: every figure of report.json in one self-contained page for people without Keel
// (a bridge or ship owner): the stage sections with their tables and plots (inline SVG), the
// same figures as the web report view, then every figure of report.json listed by its JSON
// pointer. No script, no external URL (nothing to fetch: styles inline, generic fonts).
//
// Numbers are printed as html_text.h says: <data value="EXACT" data-pointer="/stages/...">
// with EXACT the text report.json holds, so each figure is in the page with exactly its value.
// The page is well-formed XML as well as HTML (every element closed, attributes quoted).
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace keel::pipeline {

inline constexpr const char* kReportHtmlFileName = "report.html";

// Pure: `report` is report.json (build_report's document); `trajectories` is trajectories.json
// (the refine stage's ATE over time) or null when there is none.
std::string render_report_html(const nlohmann::ordered_json& report,
                               const nlohmann::json& trajectories = nullptr);

// Writes report.json and report.html (render_report_html, with the work folder's
// trajectories.json when one parses) into `work_dir`; returns their file names. Throws
// std::runtime_error naming the file that could not be written.
std::vector<std::string> write_report_files(const std::filesystem::path& work_dir,
                                            const nlohmann::ordered_json& report);

}  // namespace keel::pipeline
