#include "worker/pipeline/option_table.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace keel::pipeline {

std::string join_names(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

std::string number_text(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%g", value);
  return text;
}

void require(bool ok, const std::string& path, const std::string& expected) {
  if (!ok) throw proto::ContractError(path + ": expected " + expected);
}

Check<double> greater_than(double bound) {
  return [bound](const double& v) {
    return std::isfinite(v) && v > bound ? std::string()
                                         : "expected a number > " + number_text(bound);
  };
}

Check<double> at_least(double bound) {
  return [bound](const double& v) {
    return std::isfinite(v) && v >= bound ? std::string()
                                          : "expected a number >= " + number_text(bound);
  };
}

Check<double> in_range(double low, double high) {
  return [low, high](const double& v) {
    return v >= low && v <= high
               ? std::string()
               : "expected a number in [" + number_text(low) + ", " + number_text(high) + "]";
  };
}

Check<double> in_open_range(double low, double high) {
  return [low, high](const double& v) {
    return v > low && v < high
               ? std::string()
               : "expected a number in (" + number_text(low) + ", " + number_text(high) + ")";
  };
}

Check<int> int_at_least(int bound) {
  return [bound](const int& v) {
    return v >= bound ? std::string() : "expected an integer >= " + std::to_string(bound);
  };
}

Check<int> int_in_range(int low, int high) {
  return [low, high](const int& v) {
    return v >= low && v <= high ? std::string()
                                 : "expected an integer in [" + std::to_string(low) + ", " +
                                       std::to_string(high) + "]";
  };
}

Check<std::string> one_of(std::vector<std::string> words) {
  return [words](const std::string& v) {
    for (const auto& w : words)
      if (v == w) return std::string();
    std::string list;
    for (size_t i = 0; i < words.size(); ++i)
      list += (i == 0 ? "" : i + 1 == words.size() ? " or " : ", ") + words[i];
    return "expected " + list + ", got '" + v + "'";
  };
}

namespace {

// A Markdown table cell: pipes escaped, line breaks as spaces.
std::string cell(std::string text) {
  std::string out;
  for (char c : text) {
    if (c == '|')
      out += "\\|";
    else if (c == '\n')
      out += ' ';
    else
      out += c;
  }
  return out;
}

std::string default_cell(const OptionMarkdownRow& row) {
  if (!row.doc.default_text.empty()) return row.doc.default_text;
  const nlohmann::json& v = row.default_value;
  if (v.is_number_float()) return number_text(v.get<double>());
  return "`" + v.dump() + "`";
}

}  // namespace

std::string render_option_markdown(const std::vector<OptionMarkdownRow>& rows) {
  std::vector<std::string> groups;
  for (const auto& row : rows)
    if (std::find(groups.begin(), groups.end(), row.doc.group) == groups.end())
      groups.push_back(row.doc.group);
  std::string out;
  for (const auto& group : groups) {
    if (!out.empty()) out += "\n";
    if (!group.empty()) out += group + "\n\n";
    out += "| option | type | default | unit | meaning | source |\n";
    out += "|---|---|---|---|---|---|\n";
    for (const auto& row : rows) {
      if (row.doc.group != group) continue;
      out += "| `" + row.name + "` | " + cell(row.type) + " | " + cell(default_cell(row)) + " | " +
             cell(row.doc.unit) + " | " + cell(row.doc.meaning) + " | " + cell(row.doc.source) +
             " |\n";
    }
  }
  return out;
}

}  // namespace keel::pipeline
