#include "worker/io/csv_reader.h"

#include <cmath>

namespace keel::io {

namespace {

std::string join(const std::vector<std::string>& names, size_t begin, size_t end) {
  std::string out;
  for (size_t i = begin; i < end; ++i) out += (i > begin ? "," : "") + names[i];
  return out;
}

std::string describe_header(const std::vector<std::string>& columns,
                            const std::vector<std::string>& optional_columns) {
  std::string text = join(columns, 0, columns.size());
  for (const auto& name : optional_columns) text += "[," + name + "]";
  return text;
}

}  // namespace

CsvReader::CsvReader(const std::filesystem::path& path, std::vector<std::string> columns,
                     std::vector<std::string> optional_columns)
    : lines_(path) {
  std::string_view header;
  const std::string expected = describe_header(columns, optional_columns);
  if (!lines_.next(header)) lines_.fail("empty file: expected header '" + expected + "'");
  split_commas(header, fields_);
  std::vector<std::string> found;
  for (auto f : fields_) found.emplace_back(trim(f));
  bool ok =
      found.size() >= columns.size() && found.size() <= columns.size() + optional_columns.size();
  for (size_t i = 0; ok && i < found.size(); ++i) {
    const std::string& want =
        i < columns.size() ? columns[i] : optional_columns[i - columns.size()];
    ok = found[i] == want;
  }
  if (!ok)
    lines_.fail("header: expected '" + expected + "', found '" + join(found, 0, found.size()) +
                "'");
  names_ = std::move(found);
}

bool CsvReader::next() {
  std::string_view line;
  while (lines_.next(line)) {
    if (trim(line).empty()) continue;
    split_commas(line, fields_);
    if (fields_.size() != names_.size())
      lines_.fail("expected " + std::to_string(names_.size()) + " columns (" +
                  join(names_, 0, names_.size()) + "), found " + std::to_string(fields_.size()));
    return true;
  }
  return false;
}

double CsvReader::number(size_t column, bool allow_nan) const {
  double value = 0.0;
  if (!parse_double(fields_[column], value))
    lines_.fail("column '" + names_[column] + "': expected a number, got '" +
                std::string(trim(fields_[column])) + "'");
  if (!allow_nan && !std::isfinite(value))
    lines_.fail("column '" + names_[column] + "': expected a finite number, got '" +
                std::string(trim(fields_[column])) + "'");
  if (allow_nan && std::isinf(value))
    lines_.fail("column '" + names_[column] + "': expected a number or nan, got '" +
                std::string(trim(fields_[column])) + "'");
  return value;
}

TimeNs CsvReader::time(size_t column) const {
  try {
    return parse_seconds_exact(fields_[column]);
  } catch (const std::exception&) {
    lines_.fail("column '" + names_[column] + "': expected time in decimal seconds, got '" +
                std::string(trim(fields_[column])) + "'");
  }
}

void CsvReader::check_increasing(TimeNs t_ns, const char* what) {
  if (have_last_ && t_ns <= last_t_ns_) {
    lines_.fail(std::string(t_ns == last_t_ns_ ? "duplicate" : "decreasing") + " timestamp " +
                what + " = " + format_seconds(t_ns) + " (line " + std::to_string(last_line_) +
                " has " + format_seconds(last_t_ns_) + "); expected strictly increasing time");
  }
  have_last_ = true;
  last_t_ns_ = t_ns;
  last_line_ = lines_.line_number();
}

}  // namespace keel::io
