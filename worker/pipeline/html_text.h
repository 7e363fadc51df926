// Text for report.html: escaping and the one way numbers are printed, so that a figure of
// report.json can be found in the page with exactly its value.
//
// A number is written as <data value="EXACT">SHOWN</data>: EXACT is the number as report.json
// spells it (nlohmann::json's dump: the shortest text that reads back as the same double;
// integers as integers; NaN and infinities as null, which is what report.json holds for them),
// SHOWN is the same value rounded for reading (format_shown). The HTML <data> element is made
// for this: a machine-readable value beside its human-readable form. A figure of report.json
// also carries data-pointer="JSON pointer (RFC 6901) of the figure in report.json", so a reader
// (or a test) can tell which figure each number is.
#pragma once

#include <nlohmann/json.hpp>

#include <string>

namespace keel::pipeline::html {

// Escapes &, <, >, " and ' for text and attribute values (HTML and XML alike).
std::string escape(const std::string& text);

// The number as report.json writes it; throws std::invalid_argument for a non-number.
std::string format_exact(const nlohmann::json& number);
// For reading: integers in full, others with 4 significant digits (no exponent between 1e-3 and
// 1e6), "null" for NaN or infinity.
std::string format_shown(double value);
// RFC 6901 escaping of one reference token ("~" -> "~0", "/" -> "~1").
std::string pointer_token(const std::string& key);

// <data value="EXACT" data-pointer="POINTER">SHOWN UNIT</data> (no data-pointer when empty).
std::string data(const nlohmann::json& number, const std::string& pointer = "",
                 const std::string& unit = "");
// A JSON value as a table cell's contents: a number as data(), a string escaped, true/false,
// null as an em dash, an array as "[a, b, c]" of its elements' cells (pointer/0, pointer/1, ..).
std::string value_cell(const nlohmann::json& value, const std::string& pointer = "",
                       const std::string& unit = "");

}  // namespace keel::pipeline::html
