// A stage's options as one table: each row names an option and says how to read it from JSON
// (`--set stage.option=value`), how to write it back, and what it means for the docs. The
// stage's `from_json`, `to_json` and its tables in docs/stage-options.md are all made from the
// rows, so an option is written once. The defaults are those of the options struct itself
// (`Options{}`): the papers' values, written once, in the struct.
//
//   const OptionTable<InspectOptions>& inspect_option_table() {
//     static const OptionTable<InspectOptions> table("inspect", {
//       number("tau_m", &InspectOptions::tau_m, at_least(0.0),
//              {"m", "tau of Algorithm 1: features farther than this from the model", "seed 001
//              Sec. 3.1"}),
//       ...});
//     return table;
//   }
//
// Errors are proto::ContractError naming the option as the user wrote it:
//   options.<stage>.<option>: expected number, got string    (the JSON type, proto::FieldReader)
//   options.<stage>.<option>: expected a number > 0          (a row's check: `require`)
//   options.<stage>.<option>: unknown option (known: a, b)   (a name no row has)
#pragma once

#include <nlohmann/json.hpp>

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "proto/contract_error.h"

namespace keel::pipeline {

// "a, b, c": for messages that list what is known.
std::string join_names(const std::vector<std::string>& names);

// What docs/stage-options.md says of one option, besides its name.
struct OptionDoc {
  // Initialised in place, so a row may name only its first fields: OptionDoc{"m", "..."}.
  std::string unit{};     // "m", "s", "deg", "" for none
  std::string meaning{};  // one paragraph (Markdown)
  std::string source{};   // where the default comes from: "seed 000 Table IV", "beyond the paper"
  std::string group{};    // the docs' sub-table this row is listed in ("" = the stage's first)
  std::string default_text{};  // overrides the default shown (else the JSON of Options{})
};

// A row's check beyond the JSON type: "" when `value` is acceptable, else the words that follow
// "options.<stage>.<option>: " in the error ("expected a number > 0").
template <typename T>
using Check = std::function<std::string(const T& value)>;

template <typename T>
Check<T> any_value() {
  return [](const T&) { return std::string(); };
}
Check<double> greater_than(double bound);                   // "expected a number > bound"
Check<double> at_least(double bound);                       // "expected a number >= bound"
Check<double> in_range(double low, double high);            // "expected a number in [low, high]"
Check<double> in_open_range(double low, double high);       // "expected a number in (low, high)"
Check<int> int_at_least(int bound);                         // "expected an integer >= bound"
Check<int> int_in_range(int low, int high);                 // "expected an integer in [low, high]"
Check<std::string> one_of(std::vector<std::string> words);  // "expected a, b or c, got 'x'"

// The text of a number as the docs and messages print it: 0.25, 1e-06, 2.
std::string number_text(double value);

template <typename Options>
struct OptionRow {
  std::string name;
  std::string type;  // for the docs: "number", "integer", "bool", "string", "array of strings"...
  OptionDoc doc;
  // Reads `value` into `options`; `path` is "options.<stage>.<name>". Throws ContractError.
  std::function<void(Options& options, const nlohmann::json& value, const std::string& path)> read;
  std::function<nlohmann::json(const Options& options)> write;
};

// Throws ContractError "`path`: `expected`" unless `ok`: the one `require` of every stage.
void require(bool ok, const std::string& path, const std::string& expected);

// One row for a member of a type FieldReader converts (bool, integers, double, std::string,
// std::vector<std::string>, nlohmann::json), with its check.
template <typename Options, typename T>
OptionRow<Options> option(const char* name, T Options::*field, Check<T> check, OptionDoc doc) {
  OptionRow<Options> row;
  row.name = name;
  if constexpr (std::is_same_v<T, bool>)
    row.type = "bool";
  else if constexpr (std::is_integral_v<T>)
    row.type = "integer";
  else if constexpr (std::is_floating_point_v<T>)
    row.type = "number";
  else if constexpr (std::is_same_v<T, std::string>)
    row.type = "string";
  else if constexpr (std::is_same_v<T, std::vector<std::string>>)
    row.type = "array of strings";
  else
    row.type = "JSON";
  row.doc = std::move(doc);
  row.read = [field, check](Options& options, const nlohmann::json& value,
                            const std::string& path) {
    T parsed = proto::FieldReader::convert<T>(value, path);
    const std::string wrong = check ? check(parsed) : std::string();
    if (!wrong.empty()) throw proto::ContractError(path + ": " + wrong);
    options.*field = std::move(parsed);
  };
  row.write = [field](const Options& options) { return nlohmann::json(options.*field); };
  return row;
}

template <typename Options, typename T>
OptionRow<Options> option(const char* name, T Options::*field, OptionDoc doc) {
  return option<Options, T>(name, field, any_value<T>(), std::move(doc));
}

// The Markdown of a table's rows (option_table.cc), shared by every OptionTable<Options>.
struct OptionMarkdownRow {
  std::string name, type;
  OptionDoc doc;
  nlohmann::json default_value;
};
std::string render_option_markdown(const std::vector<OptionMarkdownRow>& rows);

// The type-free face of a table, for the registry, the docs and `keel-worker options`.
class OptionsSchema {
 public:
  virtual ~OptionsSchema() = default;
  virtual const std::string& stage() const = 0;
  // Reads `options` as the stage will (throws ContractError as the stage would).
  virtual void check(const nlohmann::json& options) const = 0;
  // Every option with its default value, in the table's order.
  virtual nlohmann::ordered_json defaults() const = 0;
  // The docs' table(s) of this stage: one Markdown table per group, in the rows' order, each
  // after a line naming its group (when the stage has more than one).
  virtual std::string markdown() const = 0;
};

template <typename Options>
class OptionTable : public OptionsSchema {
 public:
  using Rows = std::vector<OptionRow<Options>>;
  // Checks that need several options at once, run after every row was read; call
  // `require(ok, "options.<stage>.<option>", expected)` to fail naming an option.
  using Validate = std::function<void(const Options& options, const std::string& stage_path)>;

  OptionTable(std::string stage, Rows rows, Validate validate = {})
      : stage_(std::move(stage)), rows_(std::move(rows)), validate_(std::move(validate)) {}

  const std::string& stage() const override { return stage_; }
  const Rows& rows() const { return rows_; }

  // `options` is the stage's object ({"option": value}); null means every default.
  Options from_json(const nlohmann::json& options) const {
    Options out;
    const std::string path = "options." + stage_;
    if (options.is_null()) return out;
    if (!options.is_object())
      throw proto::ContractError(path + ": expected object, got " + proto::json_type_name(options));
    for (const auto& item : options.items()) {
      const OptionRow<Options>* row = find(item.key());
      if (!row)
        throw proto::ContractError(path + "." + item.key() +
                                   ": unknown option (known: " + join_names(names()) + ")");
    }
    // In the table's order, so the first wrong option named is the same whatever the JSON's.
    for (const auto& row : rows_)
      if (options.contains(row.name)) row.read(out, options.at(row.name), path + "." + row.name);
    if (validate_) validate_(out, path);
    return out;
  }

  nlohmann::ordered_json to_json(const Options& options) const {
    nlohmann::ordered_json out = nlohmann::ordered_json::object();
    for (const auto& row : rows_) out[row.name] = row.write(options);
    return out;
  }

  void check(const nlohmann::json& options) const override { (void)from_json(options); }
  nlohmann::ordered_json defaults() const override { return to_json(Options{}); }

  std::string markdown() const override {
    std::vector<OptionMarkdownRow> rows;
    const Options defaults{};
    for (const auto& row : rows_)
      rows.push_back({row.name, row.type, row.doc, row.write(defaults)});
    return render_option_markdown(rows);
  }

  std::vector<std::string> names() const {
    std::vector<std::string> out;
    for (const auto& row : rows_) out.push_back(row.name);
    return out;
  }

 private:
  const OptionRow<Options>* find(const std::string& name) const {
    for (const auto& row : rows_)
      if (row.name == name) return &row;
    return nullptr;
  }

  std::string stage_;
  Rows rows_;
  Validate validate_;
};

}  // namespace keel::pipeline
