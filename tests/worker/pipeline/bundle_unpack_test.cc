#include "worker/pipeline/bundle_unpack.h"
#include "tests/temp_dir.h"

#include <archive.h>
#include <archive_entry.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <sstream>

namespace keel::pipeline {
namespace {

namespace fs = std::filesystem;

// One member of a tar built by the test.
struct Member {
  std::string name;
  mode_t type = AE_IFREG;
  std::string content;   // regular files
  std::string link;      // symlink target
  std::string hardlink;  // hard link target (type ignored)
};

Member file(std::string name, std::string content) {
  Member m;
  m.name = std::move(name);
  m.content = std::move(content);
  return m;
}
Member special(std::string name, mode_t type) {
  Member m;
  m.name = std::move(name);
  m.type = type;
  return m;
}
Member dir(std::string name) { return special(std::move(name), AE_IFDIR); }
Member symlink(std::string name, std::string target) {
  Member m = special(std::move(name), AE_IFLNK);
  m.link = std::move(target);
  return m;
}
Member hardlink(std::string name, std::string target) {
  Member m;
  m.name = std::move(name);
  m.hardlink = std::move(target);
  return m;
}

// Writes `members` as a pax tar (gzip-compressed when asked) with libarchive.
void write_tar(const fs::path& path, const std::vector<Member>& members, bool gzip = false) {
  archive* a = archive_write_new();
  archive_write_set_format_pax_restricted(a);
  if (gzip) archive_write_add_filter_gzip(a);
  ASSERT_EQ(archive_write_open_filename(a, path.c_str()), ARCHIVE_OK) << archive_error_string(a);
  for (const auto& m : members) {
    archive_entry* e = archive_entry_new();
    archive_entry_set_pathname(e, m.name.c_str());
    archive_entry_set_perm(e, m.type == AE_IFDIR ? 0755 : 0644);
    if (!m.hardlink.empty()) {
      archive_entry_set_filetype(e, AE_IFREG);
      archive_entry_set_hardlink(e, m.hardlink.c_str());
      archive_entry_set_size(e, 0);
    } else {
      archive_entry_set_filetype(e, m.type);
      if (m.type == AE_IFLNK) archive_entry_set_symlink(e, m.link.c_str());
      archive_entry_set_size(e, m.type == AE_IFREG ? static_cast<la_int64_t>(m.content.size()) : 0);
    }
    ASSERT_EQ(archive_write_header(a, e), ARCHIVE_OK) << archive_error_string(a);
    if (m.type == AE_IFREG && !m.content.empty() && m.hardlink.empty()) {
      ASSERT_EQ(archive_write_data(a, m.content.data(), m.content.size()),
                static_cast<la_ssize_t>(m.content.size()));
    }
    archive_entry_free(e);
  }
  archive_write_close(a);
  archive_write_free(a);
}

using keel::testing::read_file;

class BundleUnpackTest : public ::testing::Test {
 protected:
  void SetUp() override {
    base_ = fs::temp_directory_path() /
            ("keel_unpack_" + std::to_string(::getpid()) + "_" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(base_);
    fs::create_directories(base_ / "tars");
    fs::create_directories(base_ / "parent");
    tar_ = base_ / "tars" / "bundle.tar";
    destination_ = base_ / "parent" / "unpacked";
  }
  void TearDown() override { fs::remove_all(base_); }

  // Unpacks and expects a BundleError whose message names `member`; then checks nothing was
  // written beside the target folder (and the target folder itself was cleaned up).
  void expect_rejected(const std::string& member, const std::string& reason,
                       const UnpackLimits& limits = {}) {
    try {
      unpack_bundle(tar_, destination_, limits);
      ADD_FAILURE() << "expected the bundle to be rejected";
    } catch (const BundleError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("member '" + member + "'"), std::string::npos) << what;
      EXPECT_NE(what.find(reason), std::string::npos) << what;
      EXPECT_NE(what.find(tar_.string()), std::string::npos) << what;
    }
    EXPECT_TRUE(fs::is_empty(base_ / "parent")) << "something was left in " << base_ / "parent";
    EXPECT_EQ(std::distance(fs::directory_iterator(base_), fs::directory_iterator()), 2)
        << "something was written beside parent/ and tars/";
  }

  fs::path base_, tar_, destination_;
};

TEST_F(BundleUnpackTest, GoodBundleInATopFolder) {
  write_tar(tar_, {dir("m/"), file("m/mission.yaml", "keel_mission: 1\n"),
                   file("m/imu.csv", "t,wx,wy,wz,ax,ay,az\n"), file("m/lidar/0001.pcd", "PCD"),
                   symlink("m/latest.pcd", "lidar/0001.pcd"),
                   hardlink("m/copy.pcd", "m/lidar/0001.pcd")});

  const fs::path root = unpack_bundle(tar_, destination_);

  EXPECT_EQ(root, fs::canonical(destination_) / "m");
  EXPECT_EQ(read_file(root / "mission.yaml"), "keel_mission: 1\n");
  EXPECT_EQ(read_file(root / "lidar" / "0001.pcd"), "PCD");
  EXPECT_EQ(read_file(root / "latest.pcd"), "PCD");
  EXPECT_TRUE(fs::is_symlink(root / "latest.pcd"));
  EXPECT_EQ(read_file(root / "copy.pcd"), "PCD");
}

TEST_F(BundleUnpackTest, GoodBundleAtTheRootAndGzipped) {
  write_tar(tar_, {dir("./"), file("./mission.yaml", "keel_mission: 1\n"), file("a/b.csv", "x")},
            /*gzip=*/true);
  const fs::path root = unpack_bundle(tar_, destination_);
  EXPECT_EQ(root, fs::canonical(destination_));
  EXPECT_EQ(read_file(root / "a" / "b.csv"), "x");
}

TEST_F(BundleUnpackTest, RejectsDotDot) {
  write_tar(tar_, {file("mission.yaml", "x"), file("../evil", "pwned")});
  expect_rejected("../evil", "'..'");
}

TEST_F(BundleUnpackTest, RejectsDotDotInTheMiddle) {
  write_tar(tar_, {file("mission.yaml", "x"), file("a/../../evil", "pwned")});
  expect_rejected("a/../../evil", "'..'");
}

TEST_F(BundleUnpackTest, RejectsAbsolutePath) {
  write_tar(tar_, {file("mission.yaml", "x"), file((base_ / "abs").string(), "pwned")});
  expect_rejected((base_ / "abs").string(), "absolute path");
  EXPECT_FALSE(fs::exists(base_ / "abs"));
}

TEST_F(BundleUnpackTest, RejectsSymlinkToEtc) {
  write_tar(tar_, {file("mission.yaml", "x"), symlink("etc", "/etc")});
  expect_rejected("etc", "absolute path '/etc'");
}

TEST_F(BundleUnpackTest, RejectsSymlinkClimbingOut) {
  write_tar(tar_, {file("mission.yaml", "x"), symlink("d/up", "../../parent")});
  expect_rejected("d/up", "points outside");
}

TEST_F(BundleUnpackTest, RejectsSymlinkChainThatEscapesOnlyWhenFollowed) {
  // Read lexically, d/a -> ../self/.. stays inside; on disk self -> "." so it climbs out.
  write_tar(tar_, {file("mission.yaml", "x"), symlink("self", "."), symlink("d/a", "../self/..")});
  expect_rejected("d/a", "resolves outside");
}

TEST_F(BundleUnpackTest, NeverWritesThroughASymlink) {
  // The link itself points inside, but a later member must not be extracted through it.
  write_tar(tar_, {file("mission.yaml", "x"), dir("real/"), symlink("via", "real"),
                   file("via/file.txt", "y")});
  expect_rejected("via/file.txt", "cannot extract");
}

TEST_F(BundleUnpackTest, RejectsHardLinkToAFileOutside) {
  std::ofstream(base_ / "tars" / "secret") << "secret";
  write_tar(tar_, {file("mission.yaml", "x"), hardlink("h", (base_ / "tars/secret").string())});
  expect_rejected("h", "hard link");
}

TEST_F(BundleUnpackTest, RejectsDeviceFile) {
  write_tar(tar_, {file("mission.yaml", "x"), special("null", AE_IFCHR)});
  expect_rejected("null", "device file not allowed");
}

TEST_F(BundleUnpackTest, RejectsFifo) {
  write_tar(tar_, {file("mission.yaml", "x"), special("pipe", AE_IFIFO)});
  expect_rejected("pipe", "FIFO not allowed");
}

TEST_F(BundleUnpackTest, RejectsTooManyEntries) {
  std::vector<Member> members = {file("mission.yaml", "x")};
  for (int i = 1; i <= 10; ++i) members.push_back(file("f" + std::to_string(i), "x"));
  write_tar(tar_, members);
  UnpackLimits limits;
  limits.max_entries = 10;
  expect_rejected("f10", "too many members (limit 10)", limits);  // the 11th member
}

TEST_F(BundleUnpackTest, RejectsTooManyBytes) {
  write_tar(tar_, {file("mission.yaml", "x"), file("big.bin", std::string(5000, 'z'))});
  UnpackLimits limits;
  limits.max_total_bytes = 4096;
  expect_rejected("big.bin", "exceeds the limit of 4096 bytes", limits);
}

TEST_F(BundleUnpackTest, RejectsDecompressionBomb) {
  // 8 MiB of zeros compress to a few KiB: the limit applies to unpacked bytes.
  write_tar(tar_, {file("mission.yaml", "x"), file("zeros.bin", std::string(8 << 20, '\0'))},
            /*gzip=*/true);
  ASSERT_LT(fs::file_size(tar_), 100u << 10);
  UnpackLimits limits;
  limits.max_total_bytes = 1 << 20;
  expect_rejected("zeros.bin", "exceeds the limit", limits);
}

TEST_F(BundleUnpackTest, BundleWithoutMissionYamlIsRejected) {
  write_tar(tar_, {file("a/imu.csv", "x"), file("b/imu.csv", "y")});
  try {
    unpack_bundle(tar_, destination_);
    FAIL() << "expected an error";
  } catch (const BundleError& e) {
    EXPECT_NE(std::string(e.what()).find("no mission.yaml"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(fs::is_empty(base_ / "parent"));
}

TEST_F(BundleUnpackTest, NotATarIsRejectedNamingTheFile) {
  std::ofstream(tar_) << "this is not a tar file at all, just some text";
  try {
    unpack_bundle(tar_, destination_);
    FAIL() << "expected an error";
  } catch (const BundleError& e) {
    EXPECT_NE(std::string(e.what()).find(tar_.string()), std::string::npos) << e.what();
  }
  EXPECT_TRUE(fs::is_empty(base_ / "parent"));
}

TEST_F(BundleUnpackTest, TruncatedTarIsRejectedNamingTheMember) {
  write_tar(tar_, {file("mission.yaml", "x"), file("big.bin", std::string(100000, 'q'))});
  fs::resize_file(tar_, 50000);
  try {
    unpack_bundle(tar_, destination_);
    FAIL() << "expected an error";
  } catch (const BundleError& e) {
    EXPECT_NE(std::string(e.what()).find("big.bin"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(fs::is_empty(base_ / "parent"));
}

TEST_F(BundleUnpackTest, NonEmptyDestinationIsRefused) {
  write_tar(tar_, {file("mission.yaml", "x")});
  fs::create_directories(destination_);
  std::ofstream(destination_ / "keep.txt") << "mine";
  EXPECT_THROW(unpack_bundle(tar_, destination_), BundleError);
  EXPECT_EQ(read_file(destination_ / "keep.txt"), "mine");
}

}  // namespace
}  // namespace keel::pipeline
