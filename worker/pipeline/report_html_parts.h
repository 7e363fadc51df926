// The pieces report.html's sections are made of (internal to report_html*.cc): a reference into
// report.json that knows its JSON pointer, tables, and the sections themselves.
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace keel::pipeline::report_html {

using Json = nlohmann::ordered_json;

// A value of report.json with its JSON pointer; a missing key or index gives null (pointer kept).
class Ref {
 public:
  Ref(const Json& value, std::string pointer) : value_(&value), pointer_(std::move(pointer)) {}
  Ref operator[](const std::string& key) const;
  Ref operator[](size_t index) const;
  const Json& json() const { return *value_; }
  const std::string& pointer() const { return pointer_; }
  bool missing() const { return value_->is_null(); }
  bool is_number() const { return value_->is_number(); }
  // The number, NaN when the value is not a number.
  double number() const;
  std::string text() const;  // a string value, else its JSON text
  // The value as a cell: numbers as <data> with this pointer (html::value_cell).
  std::string cell(const std::string& unit = "") const;
  std::vector<double> numbers() const;  // an array of numbers (NaN for others), else empty

 private:
  const Json* value_;
  std::string pointer_;
};

struct Table {
  std::string id;                 // the id attribute, for links and tests; may be empty
  std::string caption;            // escaped by render
  std::vector<std::string> head;  // HTML
  std::vector<std::vector<std::string>> rows;  // HTML cells
};
std::string render(const Table& table);

// <h3>, <p> with escaped text; a list of report strings (warnings) as <ul>.
std::string heading(const std::string& text, const std::string& id = "");
std::string paragraph(const std::string& text);
std::string string_list(const Ref& list, const std::string& title);
// A figure wrapper: the SVG and a caption (escaped).
std::string figure(const std::string& svg, const std::string& caption);

// The stage sections; each returns an <section> element.
std::string ingest_section(const Ref& stage);
std::string compare_section(const Ref& stage);
// Every leaf of report.json as a table row (pointer, value).
std::string all_figures(const Ref& report);

}  // namespace keel::pipeline::report_html
