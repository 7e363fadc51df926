#include "worker/io/bag/rosbag2_metadata.h"

#include <yaml-cpp/yaml.h>

#include "worker/io/display_path.h"
#include "worker/io/io_error.h"
#include "worker/io/text_lines.h"

namespace keel::io {

namespace fs = std::filesystem;

namespace {

template <typename T>
T scalar(const YAML::Node& node, const std::string& key, const std::string& where, T fallback,
         bool required) {
  const YAML::Node value = node[key];
  if (!value) {
    if (required) throw IoError(where + ": missing key '" + key + "'");
    return fallback;
  }
  try {
    return value.as<T>();
  } catch (const YAML::Exception&) {
    throw IoError(where + ": key '" + key + "' is not a " +
                  (std::is_same_v<T, std::string> ? "string" : "number"));
  }
}

}  // namespace

Rosbag2Metadata read_rosbag2_metadata(const fs::path& metadata_yaml) {
  const std::string name = display_path(metadata_yaml);
  YAML::Node document;
  try {
    document = YAML::Load(read_file_bytes(metadata_yaml));
  } catch (const YAML::Exception& e) {
    throw IoError(name + ":" + std::to_string(e.mark.line + 1) + ": not valid YAML: " + e.msg);
  }
  const YAML::Node info = document["rosbag2_bagfile_information"];
  if (!info || !info.IsMap())
    throw IoError(name + ": no 'rosbag2_bagfile_information' map (not a rosbag2 metadata.yaml)");
  const std::string where = name + ": rosbag2_bagfile_information";
  Rosbag2Metadata m;
  m.version = scalar<int>(info, "version", where, 0, true);
  m.storage_identifier = scalar<std::string>(info, "storage_identifier", where, "", true);
  m.compression_format = scalar<std::string>(info, "compression_format", where, "", false);
  m.compression_mode = scalar<std::string>(info, "compression_mode", where, "", false);
  m.message_count = scalar<uint64_t>(info, "message_count", where, 0, false);
  if (m.storage_identifier != "mcap" && m.storage_identifier != "sqlite3")
    throw IoError(where + ".storage_identifier: '" + m.storage_identifier +
                  "' is not a storage Keel reads (mcap, sqlite3)");
  const YAML::Node files = info["relative_file_paths"];
  if (!files || !files.IsSequence() || files.size() == 0)
    throw IoError(where + ".relative_file_paths: expected a list of at least one file");
  for (size_t i = 0; i < files.size(); ++i) {
    const std::string field = where + ".relative_file_paths[" + std::to_string(i) + "]";
    if (!files[i].IsScalar()) throw IoError(field + ": expected a file name");
    const std::string file = files[i].as<std::string>();
    const fs::path rel = fs::path(file).lexically_normal();
    if (file.empty() || rel.is_absolute() || *rel.begin() == "..")
      throw IoError(field + ": '" + file + "' must be a relative path inside the bag folder");
    m.relative_file_paths.push_back(file);
  }
  const YAML::Node topics = info["topics_with_message_count"];
  if (topics && topics.IsSequence()) {
    for (size_t i = 0; i < topics.size(); ++i) {
      const std::string item = where + ".topics_with_message_count[" + std::to_string(i) + "]";
      const YAML::Node topic = topics[i]["topic_metadata"];
      if (!topic || !topic.IsMap()) throw IoError(item + ": missing topic_metadata");
      Rosbag2TopicMetadata t;
      t.name = scalar<std::string>(topic, "name", item + ".topic_metadata", "", true);
      t.type = scalar<std::string>(topic, "type", item + ".topic_metadata", "", true);
      t.serialization_format =
          scalar<std::string>(topic, "serialization_format", item + ".topic_metadata", "", false);
      t.message_count = scalar<uint64_t>(topics[i], "message_count", item, 0, false);
      m.topics.push_back(std::move(t));
    }
  }
  return m;
}

}  // namespace keel::io
