// The partial files of open uploads: uploads/<upload id>.part. A chunk is written at the
// committed offset and fsynced before the store commits the new offset, so after a crash
// the file can only be *longer* than the committed offset; truncate_to() cuts such
// uncommitted bytes so a resumed upload is byte-exact.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace keel::storage {

class UploadArea {
 public:
  explicit UploadArea(std::filesystem::path dir);  // creates the folder if needed

  std::filesystem::path part_path(const std::string& upload_id) const;
  // Creates an empty part file (durably: the folder is fsynced).
  void create(const std::string& upload_id);
  // Cuts the file to `committed` bytes, writes `size` bytes there and fsyncs. On a failed
  // write (a full disk) the file is cut back to `committed` bytes and the error rethrown.
  void write_chunk(const std::string& upload_id, int64_t committed, const char* data, size_t size);
  // Cuts bytes beyond `committed` (created if missing) and returns the file's size, which is
  // less than `committed` only if bytes acknowledged earlier were lost.
  int64_t truncate_to(const std::string& upload_id, int64_t committed);
  void remove(const std::string& upload_id);  // no error if absent
  // Upload ids that have a part file.
  std::vector<std::string> part_ids() const;

 private:
  std::filesystem::path dir_;
};

}  // namespace keel::storage
