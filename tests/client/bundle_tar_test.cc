// Deterministic mission tars: checked by reading them back with libarchive's reader.
#include "client/bundle_tar.h"

#include <archive.h>
#include <archive_entry.h>
#include <gtest/gtest.h>

#include <chrono>

#include "tests/temp_dir.h"

namespace keel::client {
namespace {

namespace fs = std::filesystem;
using keel::testing::read_file;
using keel::testing::TempDir;
using keel::testing::write_file;

struct TarItem {
  std::string name;
  bool is_directory;
  int mode;
  int64_t mtime;
  int64_t uid;
  int64_t gid;
  std::string content;
};

std::vector<TarItem> read_tar(const fs::path& tar) {
  archive* a = archive_read_new();
  archive_read_support_format_tar(a);
  EXPECT_EQ(archive_read_open_filename(a, tar.c_str(), 1 << 16), ARCHIVE_OK);
  std::vector<TarItem> items;
  archive_entry* entry;
  while (archive_read_next_header(a, &entry) == ARCHIVE_OK) {
    TarItem item{archive_entry_pathname(entry),
                 archive_entry_filetype(entry) == AE_IFDIR,
                 static_cast<int>(archive_entry_perm(entry)),
                 archive_entry_mtime(entry),
                 archive_entry_uid(entry),
                 archive_entry_gid(entry),
                 ""};
    char buffer[4096];
    la_ssize_t n;
    while ((n = archive_read_data(a, buffer, sizeof(buffer))) > 0) item.content.append(buffer, n);
    items.push_back(item);
  }
  archive_read_free(a);
  return items;
}

// The same mission written in two different orders with different mtimes and modes.
void write_mission(const fs::path& root, bool reversed) {
  std::vector<std::pair<std::string, std::string>> files = {
      {"mission.yaml", "keel_mission: 1\nname: m1\n"},
      {"imu.csv", "t,wx,wy,wz,ax,ay,az\n0.0,0,0,0,0,0,9.81\n"},
      {"lidar/index.csv", "t,file\n0.0,0000.pcd\n"},
      {"lidar/0000.pcd", std::string(70000, 'p')},
      {"ground_truth/trajectory.tum", "0 0 0 0 0 0 0 1\n"}};
  if (reversed) std::reverse(files.begin(), files.end());
  int i = 0;
  for (const auto& [name, content] : files) {
    write_file(root / name, content);
    fs::last_write_time(
        root / name, fs::file_time_type::clock::now() - std::chrono::hours(reversed ? 100 + i : i));
    fs::permissions(root / name, reversed ? fs::perms(0600) : fs::perms(0664));
    ++i;
  }
}

TEST(BundleTar, SameFolderContentGivesTheSameBytes) {
  TempDir dir;
  write_mission(dir.path() / "a", false);
  write_mission(dir.path() / "b", true);
  write_bundle_tar(dir.path() / "a", dir.path() / "a1.tar");
  write_bundle_tar(dir.path() / "a", dir.path() / "a2.tar");
  write_bundle_tar(dir.path() / "b", dir.path() / "b.tar");
  const std::string a1 = read_file(dir.path() / "a1.tar");
  EXPECT_FALSE(a1.empty());
  EXPECT_EQ(a1, read_file(dir.path() / "a2.tar"));
  EXPECT_EQ(a1, read_file(dir.path() / "b.tar")) << "file order, mtimes and modes must not matter";

  write_file(dir.path() / "b" / "imu.csv", "t,wx,wy,wz,ax,ay,az\n0.0,0,0,0,0,0,9.80\n");
  write_bundle_tar(dir.path() / "b", dir.path() / "b2.tar");
  EXPECT_NE(a1, read_file(dir.path() / "b2.tar")) << "content must matter";
}

TEST(BundleTar, EntriesAreSortedWithZeroedMetadataAndExactContent) {
  TempDir dir;
  write_mission(dir.path() / "m", true);
  write_bundle_tar(dir.path() / "m", dir.path() / "m.tar");
  const auto items = read_tar(dir.path() / "m.tar");
  std::vector<std::string> names;
  for (const auto& item : items) names.push_back(item.name);
  // Byte order: "ground_truth" < "ground_truth/…" < "imu.csv" < "lidar" < "lidar/0000.pcd" …
  // GNU tar writes folders with a trailing '/'.
  EXPECT_EQ(names, (std::vector<std::string>{"ground_truth/", "ground_truth/trajectory.tum",
                                             "imu.csv", "lidar/", "lidar/0000.pcd",
                                             "lidar/index.csv", "mission.yaml"}));
  for (const auto& item : items) {
    EXPECT_EQ(item.mtime, 0) << item.name;
    EXPECT_EQ(item.uid, 0) << item.name;
    EXPECT_EQ(item.gid, 0) << item.name;
    EXPECT_EQ(item.mode, item.is_directory ? 0755 : 0644) << item.name;
  }
  EXPECT_TRUE(items[0].is_directory);
  EXPECT_EQ(items[4].content, std::string(70000, 'p'));
  EXPECT_EQ(items[6].content, "keel_mission: 1\nname: m1\n");
}

TEST(BundleTar, SymlinkLeavingTheFolderIsRefused) {
  TempDir dir;
  write_mission(dir.path() / "m", false);
  write_file(dir.path() / "secret.txt", "outside");
  fs::create_symlink(dir.path() / "secret.txt", dir.path() / "m" / "link.txt");
  try {
    write_bundle_tar(dir.path() / "m", dir.path() / "m.tar");
    FAIL() << "expected LocalFileError";
  } catch (const LocalFileError& e) {
    EXPECT_NE(std::string(e.what()).find("link.txt"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("outside the mission folder"), std::string::npos)
        << e.what();
  }
  // A relative link climbing out is refused too.
  fs::remove(dir.path() / "m" / "link.txt");
  fs::create_symlink("../../secret.txt", dir.path() / "m" / "lidar" / "up.txt");
  EXPECT_THROW(write_bundle_tar(dir.path() / "m", dir.path() / "m.tar"), LocalFileError);
}

TEST(BundleTar, SymlinkInsideTheFolderIsStoredAsTheFileItPointsTo) {
  TempDir dir;
  write_mission(dir.path() / "m", false);
  fs::create_symlink("imu.csv", dir.path() / "m" / "imu_link.csv");
  write_bundle_tar(dir.path() / "m", dir.path() / "m.tar");
  for (const auto& item : read_tar(dir.path() / "m.tar"))
    if (item.name == "imu_link.csv") {
      EXPECT_FALSE(item.is_directory);
      EXPECT_EQ(item.content, read_file(dir.path() / "m" / "imu.csv"));
      return;
    }
  FAIL() << "imu_link.csv missing from the tar";
}

TEST(BundleTar, MissingFolderIsALocalFileError) {
  TempDir dir;
  EXPECT_THROW(write_bundle_tar(dir.path() / "absent", dir.path() / "x.tar"), LocalFileError);
}

TEST(BundleTar, CacheCopyIsNamedAfterItsContent) {
  TempDir dir;
  write_mission(dir.path() / "m", false);
  const fs::path first = write_bundle_to_cache(dir.path() / "m", dir.path() / "cache");
  const fs::path second = write_bundle_to_cache(dir.path() / "m", dir.path() / "cache");
  EXPECT_EQ(first, second);
  EXPECT_EQ(first.extension(), ".tar");
  EXPECT_EQ(first.stem().string().size(), 64u);
  int files = 0;
  for (const auto& item : fs::directory_iterator(dir.path() / "cache"))
    files += item.is_regular_file();
  EXPECT_EQ(files, 1) << "no temporary files left behind";
}

}  // namespace
}  // namespace keel::client
