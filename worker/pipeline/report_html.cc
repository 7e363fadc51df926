// report.html, the document: head and style, the job's summary, one section per stage in the
// job's order, then every figure of report.json (all_figures). The stages' sections are in
// report_html_<stage>.cc.
#include "worker/pipeline/report_html.h"

#include <cmath>

#include "worker/pipeline/html_text.h"
#include "worker/pipeline/report_html_parts.h"

namespace keel::pipeline {

namespace report_html {

namespace {

const Json& null_json() {
  static const Json null;
  return null;
}

constexpr const char* kStyle =
    "body{font-family:sans-serif;margin:24px auto;max-width:1100px;color:#222;line-height:1.4}"
    "h1{font-size:22px}h2{font-size:19px;border-bottom:2px solid #1f77b4;margin-top:36px}"
    "h3{font-size:15px;margin-top:22px}"
    "table{border-collapse:collapse;margin:8px 0 16px;font-size:13px}"
    "caption{text-align:left;font-weight:bold;padding:4px 0}"
    "th,td{border:1px solid #ccc;padding:3px 8px;text-align:left;vertical-align:top}"
    "th{background:#f2f4f7}td data{font-variant-numeric:tabular-nums}"
    "figure{margin:8px 0 18px}figcaption{font-size:12px;color:#555;max-width:640px}"
    ".failed{background:#fdecea;border:1px solid #d62728;padding:8px 12px}"
    ".warn li{color:#8a4b00}details summary{cursor:pointer;font-weight:bold}"
    "code{font-size:12px}";

// One row per leaf below `ref`.
void collect_leaves(const Ref& ref, std::vector<std::vector<std::string>>& rows) {
  const Json& value = ref.json();
  if (value.is_object() && !value.empty()) {
    for (const auto& item : value.items()) collect_leaves(ref[item.key()], rows);
    return;
  }
  if (value.is_array() && !value.empty()) {
    for (size_t i = 0; i < value.size(); ++i) collect_leaves(ref[i], rows);
    return;
  }
  rows.push_back({"<code>" + html::escape(ref.pointer()) + "</code>", ref.cell()});
}

std::string summary_section(const Ref& report) {
  std::string out = "<section id=\"summary\">";
  const Ref job = report["job"];
  const Ref mission = report["mission"];
  Table t{"job", "Job", {"", ""}, {}};
  t.rows.push_back({"job", job["id"].cell()});
  if (!mission["name"].missing()) t.rows.push_back({"mission", mission["name"].cell()});
  if (!mission["id"].missing()) t.rows.push_back({"mission id", mission["id"].cell()});
  if (!mission["path"].missing()) t.rows.push_back({"mission folder", mission["path"].cell()});
  std::string stages;
  for (const auto& s : job["stages"].json()) stages += (stages.empty() ? "" : ", ") + s.dump();
  t.rows.push_back({"stages", html::escape(stages)});
  if (!job["attempts"].missing()) t.rows.push_back({"attempts", job["attempts"].cell()});
  out += render(t);
  const Ref failed = report["failed"];
  if (!failed.missing())
    out += "<p class=\"failed\" id=\"failure\"><strong>The job failed in stage " +
           html::escape(failed["stage"].text()) + ":</strong> " +
           html::escape(failed["error"].text()) +
           ". The figures below are those of the stages that finished.</p>";
  Table times{"stage-seconds", "Time per stage", {"stage", "wall time"}, {}};
  for (const auto& item : report["stage_seconds"].json().items())
    times.rows.push_back({html::escape(item.key()), report["stage_seconds"][item.key()].cell("s")});
  if (!times.rows.empty()) out += render(times);
  return out + "</section>";
}

}  // namespace

Ref Ref::operator[](const std::string& key) const {
  const std::string pointer = pointer_ + "/" + html::pointer_token(key);
  if (value_->is_object()) {
    const auto it = value_->find(key);
    if (it != value_->end()) return Ref(*it, pointer);
  }
  return Ref(null_json(), pointer);
}

Ref Ref::operator[](size_t index) const {
  const std::string pointer = pointer_ + "/" + std::to_string(index);
  if (value_->is_array() && index < value_->size()) return Ref((*value_)[index], pointer);
  return Ref(null_json(), pointer);
}

double Ref::number() const { return value_->is_number() ? value_->get<double>() : std::nan(""); }

std::string Ref::text() const {
  return value_->is_string() ? value_->get<std::string>() : value_->dump();
}

std::string Ref::cell(const std::string& unit) const {
  return html::value_cell(*value_, pointer_, unit);
}

std::vector<double> Ref::numbers() const {
  std::vector<double> out;
  if (!value_->is_array()) return out;
  for (const auto& v : *value_) out.push_back(v.is_number() ? v.get<double>() : std::nan(""));
  return out;
}

std::string render(const Table& table) {
  std::string out = "<table";
  if (!table.id.empty()) out += " id=\"" + html::escape(table.id) + "\"";
  out += ">";
  if (!table.caption.empty()) out += "<caption>" + html::escape(table.caption) + "</caption>";
  bool head = false;
  for (const auto& h : table.head) head = head || !h.empty();
  if (head) {
    out += "<thead><tr>";
    for (const auto& h : table.head) out += "<th>" + h + "</th>";
    out += "</tr></thead>";
  }
  out += "<tbody>";
  for (const auto& row : table.rows) {
    out += "<tr>";
    for (size_t i = 0; i < row.size(); ++i)
      out += (i == 0 && !head ? "<th>" : "<td>") + row[i] + (i == 0 && !head ? "</th>" : "</td>");
    out += "</tr>";
  }
  return out + "</tbody></table>";
}

std::string heading(const std::string& text, const std::string& id) {
  return id.empty() ? "<h3>" + html::escape(text) + "</h3>"
                    : "<h3 id=\"" + html::escape(id) + "\">" + html::escape(text) + "</h3>";
}

std::string paragraph(const std::string& text) { return "<p>" + html::escape(text) + "</p>"; }

std::string string_list(const Ref& list, const std::string& title) {
  if (!list.json().is_array() || list.json().empty()) return "";
  std::string out = "<div class=\"warn\"><strong>" + html::escape(title) + "</strong><ul>";
  for (size_t i = 0; i < list.json().size(); ++i) out += "<li>" + list[i].cell() + "</li>";
  return out + "</ul></div>";
}

std::string figure(const std::string& svg, const std::string& caption) {
  return "<figure>" + svg + "<figcaption>" + html::escape(caption) + "</figcaption></figure>";
}

std::string all_figures(const Ref& report) {
  Table t{"all-figures", "", {"JSON pointer in report.json", "value"}, {}};
  collect_leaves(report, t.rows);
  return "<section id=\"all\"><h2>Every figure of report.json</h2><details><summary>" +
         std::to_string(t.rows.size()) + " values, by JSON pointer</summary>" + render(t) +
         "</details></section>";
}

}  // namespace report_html

std::string render_report_html(const nlohmann::ordered_json& report,
                               const nlohmann::json& trajectories) {
  using namespace report_html;
  const Ref root(report, "");
  const Ref mission = root["mission"];
  const std::string name =
      mission["name"].json().is_string() ? mission["name"].text() : root["job"]["id"].text();
  std::string page =
      "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"/>"
      "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\"/>"
      "<title>Keel report: " +
      html::escape(name) + "</title><style>" + kStyle + "</style></head><body>";
  page += "<h1>Keel report: " + html::escape(name) + "</h1>";
  page += summary_section(root);
  const Ref stages = root["stages"];
  for (const auto& item : stages.json().items()) {
    const std::string& stage = item.key();
    const Ref section = stages[stage];
    page +=
        "<section id=\"stage-" + html::escape(stage) + "\"><h2>" + html::escape(stage) + "</h2>";
    if (stage == "ingest") page += ingest_section(section);
    if (stage == "refine") page += refine_section(section, trajectories);
    if (stage == "map") page += map_section(section);
    if (stage == "ba") page += ba_section(section);
    if (stage == "inspect") page += inspect_section(section);
    if (stage == "compare") page += compare_section(section);
    page += "</section>";
  }
  page += all_figures(root);
  return page + "</body></html>\n";
}

}  // namespace keel::pipeline
