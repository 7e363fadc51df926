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

#include <string>

namespace keel::pipeline {

inline constexpr const char* kReportHtmlFileName = "report.html";

// Pure: `report` is report.json (build_report's document); `trajectories` is trajectories.json
// (the refine stage's ATE over time) or null when there is none.
std::string render_report_html(const nlohmann::ordered_json& report,
                               const nlohmann::json& trajectories = nullptr);

}  // namespace keel::pipeline
