#include "core/replaced_file.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>

namespace keel::io {
namespace {

namespace fs = std::filesystem;

fs::path scratch() {
  const fs::path dir = fs::temp_directory_path() / ("keel_replaced_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

std::string content(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(ReplacedFile, CommitPutsTheBytesInPlaceAndLeavesNoTemporary) {
  const fs::path path = scratch() / "a.bin";
  write_file_replacing(path, std::string("abc\0def", 7));
  EXPECT_EQ(content(path), std::string("abc\0def", 7));
  EXPECT_FALSE(fs::exists(path.string() + ".partial"));
  fs::remove_all(scratch());
}

TEST(ReplacedFile, AnAbandonedWriteKeepsTheOldFileWhole) {
  const fs::path path = scratch() / "b.bin";
  write_file_replacing(path, "old content");
  {
    ReplacedFile file(path);
    file.append("new", 3);
    EXPECT_TRUE(fs::exists(path.string() + ".partial"));
  }  // no commit(): a failure between append and commit
  EXPECT_EQ(content(path), "old content");
  EXPECT_FALSE(fs::exists(path.string() + ".partial"));
  fs::remove_all(scratch());
}

TEST(ReplacedFile, AMissingFolderIsNamedWithTheReason) {
  const fs::path path = scratch() / "no_such_folder" / "c.bin";
  try {
    write_file_replacing(path, "x");
    FAIL() << "expected std::runtime_error";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path.string()), std::string::npos) << what;
    EXPECT_NE(what.find("No such file or directory"), std::string::npos) << what;
  }
  fs::remove_all(scratch());
}

}  // namespace
}  // namespace keel::io
