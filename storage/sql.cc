#include "storage/sql.h"

#include <cstdlib>
#include <stdexcept>

namespace keel::storage {

bool SqlRow::is_null(int column) const {
  return std::holds_alternative<std::monostate>(cells_.at(column));
}

std::string SqlRow::text(int column) const {
  const Cell& cell = cells_.at(column);
  if (const auto* text = std::get_if<std::string>(&cell)) return *text;
  if (const auto* number = std::get_if<int64_t>(&cell)) return std::to_string(*number);
  if (const auto* number = std::get_if<double>(&cell)) return std::to_string(*number);
  return "";
}

int64_t SqlRow::int64(int column) const {
  const Cell& cell = cells_.at(column);
  if (const auto* number = std::get_if<int64_t>(&cell)) return *number;
  if (const auto* number = std::get_if<double>(&cell)) return static_cast<int64_t>(*number);
  if (const auto* text = std::get_if<std::string>(&cell))
    return std::strtoll(text->c_str(), nullptr, 10);
  return 0;
}

double SqlRow::real(int column) const {
  const Cell& cell = cells_.at(column);
  if (const auto* number = std::get_if<double>(&cell)) return *number;
  if (const auto* number = std::get_if<int64_t>(&cell)) return static_cast<double>(*number);
  if (const auto* text = std::get_if<std::string>(&cell))
    return std::strtod(text->c_str(), nullptr);
  return 0.0;
}

std::optional<SqlRow> SqlTx::row(const std::string& sql, const std::vector<SqlValue>& params) {
  SqlRows rows = query(sql, params);
  if (rows.empty()) return std::nullopt;
  return std::move(rows.front());
}

std::string translate_sql(const std::string& sql, const SqlFragments& fragments, bool dollar) {
  std::string out;
  out.reserve(sql.size() + 32);
  bool quoted = false;
  for (size_t i = 0; i < sql.size(); ++i) {
    const char c = sql[i];
    if (c == '\'') quoted = !quoted;
    if (!quoted && c == '{') {
      const size_t end = sql.find('}', i);
      const auto fill = fragments.find(sql.substr(i + 1, end - i - 1));
      if (end == std::string::npos || fill == fragments.end())
        throw std::logic_error("SQL names an unknown fragment: " + sql);
      out += fill->second;
      i = end;
    } else {
      out += (!quoted && dollar && c == '?') ? '$' : c;
    }
  }
  return out;
}

}  // namespace keel::storage
