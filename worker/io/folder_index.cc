#include "worker/io/folder_index.h"

#include "worker/io/csv_reader.h"
#include "worker/io/display_path.h"
#include "worker/io/text_writer.h"

namespace keel::io {

namespace fs = std::filesystem;

std::vector<IndexEntry> read_folder_index(const fs::path& folder) {
  CsvReader csv(folder / "index.csv", {"t", "file"});
  std::vector<IndexEntry> entries;
  std::vector<std::string_view> fields;
  while (csv.next()) {
    IndexEntry e;
    e.t_ns = csv.time(0);
    csv.check_increasing(e.t_ns);
    e.line = csv.line_number();
    const std::string name(trim(csv.field(1)));
    const fs::path rel(name);
    if (name.empty() || rel.is_absolute() || rel.lexically_normal().string().rfind("..", 0) == 0)
      csv.fail("file '" + name + "': expected a file name inside the folder");
    e.path = (folder / rel).lexically_normal();
    std::error_code ec;
    if (!fs::is_regular_file(e.path, ec))
      csv.fail("file '" + name + "' not found (" + display_path(e.path) + ")");
    entries.push_back(std::move(e));
  }
  return entries;
}

void write_folder_index(const fs::path& folder, const std::vector<IndexEntry>& entries) {
  TextWriter w(folder / "index.csv");
  w.text("t,file\n");
  for (const auto& e : entries) {
    const fs::path rel = e.path.is_absolute() ? e.path.lexically_relative(folder) : e.path;
    w.seconds(e.t_ns).text(",").text(rel.generic_string()).text("\n");
  }
  w.close();
}

}  // namespace keel::io
