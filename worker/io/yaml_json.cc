#include "worker/io/yaml_json.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <limits>
#include <regex>

#include "worker/io/display_path.h"
#include "worker/io/io_error.h"
#include "worker/io/text_lines.h"

namespace keel::io {

namespace {

std::string where(const std::string& source, const YAML::Mark& mark) {
  return source + ":" + std::to_string(mark.line + 1) + ":" + std::to_string(mark.column + 1);
}

// YAML 1.2 core schema for plain scalars.
nlohmann::json plain_scalar(const std::string& text) {
  static const std::regex kInt("[-+]?[0-9]+");
  static const std::regex kFloat(R"([-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?)");
  if (text.empty() || text == "~" || text == "null" || text == "Null" || text == "NULL")
    return nullptr;
  if (text == "true" || text == "True" || text == "TRUE") return true;
  if (text == "false" || text == "False" || text == "FALSE") return false;
  if (std::regex_match(text, kInt)) {
    int64_t value = 0;
    if (parse_int64(text, value)) return value;
  }
  if (std::regex_match(text, kFloat)) {
    double value = 0;
    if (parse_double(text, value)) return value;
  }
  if (text == ".nan" || text == ".NaN" || text == ".NAN")
    return std::numeric_limits<double>::quiet_NaN();
  if (text == ".inf" || text == "+.inf" || text == ".Inf")
    return std::numeric_limits<double>::infinity();
  if (text == "-.inf" || text == "-.Inf") return -std::numeric_limits<double>::infinity();
  return text;
}

nlohmann::json convert(const YAML::Node& node, const std::string& source) {
  switch (node.Type()) {
    case YAML::NodeType::Undefined:
    case YAML::NodeType::Null:
      return nullptr;
    case YAML::NodeType::Scalar:
      // yaml-cpp tags plain scalars "?" and quoted ones "!".
      return node.Tag() == "!" ? nlohmann::json(node.Scalar()) : plain_scalar(node.Scalar());
    case YAML::NodeType::Sequence: {
      nlohmann::json array = nlohmann::json::array();
      for (const auto& item : node) array.push_back(convert(item, source));
      return array;
    }
    case YAML::NodeType::Map: {
      nlohmann::json object = nlohmann::json::object();
      for (const auto& item : node) {
        if (!item.first.IsScalar())
          throw IoError(where(source, item.first.Mark()) + ": expected a plain key");
        const std::string key = item.first.Scalar();
        if (object.contains(key))
          throw IoError(where(source, item.first.Mark()) + ": duplicate key '" + key + "'");
        object[key] = convert(item.second, source);
      }
      return object;
    }
  }
  return nullptr;
}

}  // namespace

nlohmann::json yaml_to_json(const std::string& yaml_text, const std::string& source_name) {
  try {
    return convert(YAML::Load(yaml_text), source_name);
  } catch (const YAML::Exception& e) {
    throw IoError(where(source_name, e.mark) + ": " + e.msg);
  }
}

nlohmann::json load_yaml_file(const std::filesystem::path& path) {
  return yaml_to_json(read_file_bytes(path), display_path(path));
}

}  // namespace keel::io
