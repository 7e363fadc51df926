#include "worker/pipeline/html_text.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace keel::pipeline::html {

std::string escape(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        // Control characters other than tab and newlines are not allowed in XML 1.0 text.
        if (static_cast<unsigned char>(c) < 0x20 && c != '\t' && c != '\n' && c != '\r')
          out += "&#xFFFD;";
        else
          out += c;
    }
  }
  return out;
}

std::string format_exact(const nlohmann::json& number) {
  if (!number.is_number())
    throw std::invalid_argument("format_exact: not a number: " + number.dump());
  return number.dump();
}

std::string format_shown(double value) {
  if (!std::isfinite(value)) return "null";
  char buffer[64];
  const double magnitude = std::fabs(value);
  if (value == std::trunc(value) && magnitude < 1e15) {
    std::snprintf(buffer, sizeof buffer, "%.0f", value);
  } else if (magnitude >= 1e-3 && magnitude < 1e6) {
    const int digits_before = static_cast<int>(std::floor(std::log10(magnitude)));
    const int decimals = std::max(0, 3 - digits_before);
    std::snprintf(buffer, sizeof buffer, "%.*f", decimals, value);
  } else {
    std::snprintf(buffer, sizeof buffer, "%.3e", value);
  }
  std::string out = buffer;
  if (out == "-0") out = "0";
  return out;
}

std::string pointer_token(const std::string& key) {
  std::string out;
  for (const char c : key) {
    if (c == '~')
      out += "~0";
    else if (c == '/')
      out += "~1";
    else
      out += c;
  }
  return out;
}

std::string data(const nlohmann::json& number, const std::string& pointer,
                 const std::string& unit) {
  const double value = number.get<double>();
  std::string shown = number.is_number_integer() || number.is_number_unsigned()
                          ? number.dump()
                          : format_shown(value);
  if (!unit.empty()) shown += " " + escape(unit);
  std::string out = "<data value=\"" + format_exact(number) + "\"";
  if (!pointer.empty()) out += " data-pointer=\"" + escape(pointer) + "\"";
  return out + ">" + shown + "</data>";
}

std::string value_cell(const nlohmann::json& value, const std::string& pointer,
                       const std::string& unit) {
  if (value.is_number()) return data(value, pointer, unit);
  if (value.is_string()) return escape(value.get<std::string>());
  if (value.is_boolean()) return value.get<bool>() ? "true" : "false";
  if (value.is_null()) return "&#8212;";
  if (value.is_array()) {
    std::string out = "[";
    for (size_t i = 0; i < value.size(); ++i) {
      if (i > 0) out += ", ";
      out += value_cell(value[i], pointer.empty() ? "" : pointer + "/" + std::to_string(i));
    }
    return out + "]" + (unit.empty() ? "" : " " + escape(unit));
  }
  return escape(value.dump());
}

}  // namespace keel::pipeline::html
