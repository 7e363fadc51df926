// The pieces of report.html's sections (report_html_parts.h).
#include "worker/pipeline/report_html_parts.h"

#include <cmath>

#include "worker/pipeline/html_text.h"

namespace keel::pipeline::report_html {

namespace {

const Json& null_json() {
  static const Json null;
  return null;
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

}  // namespace keel::pipeline::report_html
