// Reads a CSV with a fixed header (docs/mission-format.md "Stream CSV files"): checks the
// header, the column count of every row, numbers, and strictly increasing time, and names
// file, line and column in every error.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "core/time.h"
#include "worker/io/text_lines.h"

namespace keel::io {

class CsvReader {
 public:
  // `columns` must appear first, in this order; `optional_columns` may follow (in order).
  CsvReader(const std::filesystem::path& path, std::vector<std::string> columns,
            std::vector<std::string> optional_columns = {});

  // Advances to the next data row (blank lines are skipped); false at the end.
  bool next();
  size_t num_columns() const { return names_.size(); }
  bool has_column(size_t column) const { return column < names_.size(); }
  // Column `column` of the current row as a number; NaN/inf fail unless allowed.
  double number(size_t column, bool allow_nan = false) const;
  // Raw text of a column of the current row.
  std::string_view field(size_t column) const { return fields_[column]; }
  // Column as exact decimal seconds -> ns.
  TimeNs time(size_t column) const;
  // Fails unless `t_ns` is later than the previous call's value (duplicate/decreasing stamps).
  void check_increasing(TimeNs t_ns, const char* what = "t");
  size_t line_number() const { return lines_.line_number(); }
  [[noreturn]] void fail(const std::string& message) const { lines_.fail(message); }

 private:
  TextLines lines_;
  std::vector<std::string> names_;
  std::vector<std::string_view> fields_;
  TimeNs last_t_ns_ = 0;
  size_t last_line_ = 0;
  bool have_last_ = false;
};

}  // namespace keel::io
