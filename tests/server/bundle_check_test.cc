#include "server/bundle_check.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <random>

#include "tests/server/tar_builder.h"

namespace keel::server {
namespace {

using testing::build_tar;
using testing::minimal_manifest;
using testing::tar_dir;
using testing::tar_file;
using testing::tar_hardlink;
using testing::tar_symlink;
using testing::TarMember;

class BundleCheckTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::random_device device;
    path_ = std::filesystem::temp_directory_path() /
            ("keel-bundle-test-" + std::to_string(device()) + ".tar");
  }
  void TearDown() override { std::filesystem::remove(path_); }

  void write(const std::string& bytes) {
    std::ofstream out(path_, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  }

  // The BundleError's code and message for `members` (fails the test if none is thrown).
  std::pair<std::string, std::string> reject(const std::vector<TarMember>& members) {
    write(build_tar(members));
    try {
      check_mission_bundle(path_);
    } catch (const BundleError& e) {
      return {e.code(), e.what()};
    }
    ADD_FAILURE() << "bundle was accepted";
    return {};
  }

  std::filesystem::path path_;
};

TEST_F(BundleCheckTest, AcceptsManifestAtRootWithFoldersAndInsideLinks) {
  write(build_tar(
      {tar_file("mission.yaml", minimal_manifest()), tar_dir("data"),
       tar_file("data/imu.csv", "t\n1\n"), tar_symlink("data/manifest", "../mission.yaml"),
       tar_symlink("latest", "data/imu.csv"), tar_hardlink("copy.csv", "data/imu.csv")}));
  BundleSummary summary = check_mission_bundle(path_);
  EXPECT_EQ(summary.members, 6);
  EXPECT_EQ(summary.file_bytes, static_cast<int64_t>(minimal_manifest().size() + 4));
}

TEST_F(BundleCheckTest, AcceptsDotSlashNamesOfEveryTarFlavour) {
  for (int format :
       {ARCHIVE_FORMAT_TAR_USTAR, ARCHIVE_FORMAT_TAR_GNUTAR, ARCHIVE_FORMAT_TAR_PAX_RESTRICTED}) {
    write(
        build_tar({tar_dir("./"), tar_file("./mission.yaml", minimal_manifest())}, false, format));
    EXPECT_NO_THROW(check_mission_bundle(path_)) << "format " << format;
  }
}

TEST_F(BundleCheckTest, RejectsDotDotMembersNamingThem) {
  auto [code, message] = reject({tar_file("mission.yaml", "x"), tar_file("../x", "evil")});
  EXPECT_EQ(code, "unsafe_path");
  EXPECT_NE(message.find("'../x'"), std::string::npos) << message;

  std::tie(code, message) =
      reject({tar_file("mission.yaml", "x"), tar_file("data/../../x", "evil")});
  EXPECT_EQ(code, "unsafe_path");
  EXPECT_NE(message.find("data/../../x"), std::string::npos) << message;
}

TEST_F(BundleCheckTest, RejectsAbsoluteMembers) {
  auto [code, message] = reject({tar_file("mission.yaml", "x"), tar_file("/etc/passwd", "root")});
  EXPECT_EQ(code, "unsafe_path");
  EXPECT_NE(message.find("/etc/passwd"), std::string::npos) << message;
}

TEST_F(BundleCheckTest, RejectsSymlinksLeavingTheBundle) {
  EXPECT_EQ(reject({tar_file("mission.yaml", "x"), tar_symlink("etc", "/etc")}).first,
            "unsafe_path");
  EXPECT_EQ(reject({tar_file("mission.yaml", "x"), tar_symlink("a/up", "../../x")}).first,
            "unsafe_path");
  EXPECT_EQ(reject({tar_file("mission.yaml", "x"), tar_symlink("up", "..")}).first, "unsafe_path");
  // 'l/..' climbs out when l is itself a symlink, so '..' after a name is refused.
  EXPECT_EQ(reject({tar_file("mission.yaml", "x"), tar_symlink("a/b", "l/../../x")}).first,
            "unsafe_path");
}

TEST_F(BundleCheckTest, RejectsMembersBelowASymlink) {
  auto [code, message] =
      reject({tar_file("mission.yaml", "x"), tar_symlink("out", "data"), tar_file("out/f", "y")});
  EXPECT_EQ(code, "unsafe_path");
  EXPECT_NE(message.find("out/f"), std::string::npos) << message;
}

TEST_F(BundleCheckTest, RejectsHardlinksToOutside) {
  EXPECT_EQ(reject({tar_file("mission.yaml", "x"), tar_hardlink("h", "../../etc/shadow")}).first,
            "unsafe_path");
  EXPECT_EQ(reject({tar_file("mission.yaml", "x"), tar_hardlink("h", "/etc/shadow")}).first,
            "unsafe_path");
}

TEST_F(BundleCheckTest, RejectsDeviceNodes) {
  TarMember device{"dev", TarMember::Kind::kCharDevice, ""};
  EXPECT_EQ(reject({tar_file("mission.yaml", "x"), device}).first, "bad_bundle");
}

TEST_F(BundleCheckTest, RequiresManifestAtTheRoot) {
  auto [code, message] = reject({tar_dir("m"), tar_file("m/mission.yaml", "x")});
  EXPECT_EQ(code, "bad_bundle");
  EXPECT_NE(message.find("mission.yaml"), std::string::npos) << message;
  EXPECT_EQ(reject({tar_dir("mission.yaml")}).first, "bad_bundle");
}

TEST_F(BundleCheckTest, RejectsNonTarAndCompressedAndTruncated) {
  write("this is not a tar file at all, just some text that is long enough to look at");
  EXPECT_THROW(check_mission_bundle(path_), BundleError);

  write(build_tar({tar_file("mission.yaml", minimal_manifest())}, /*gzip=*/true));
  try {
    check_mission_bundle(path_);
    ADD_FAILURE() << "gzip accepted";
  } catch (const BundleError& e) {
    EXPECT_EQ(e.code(), "bad_bundle");
  }

  std::string tar = build_tar(
      {tar_file("mission.yaml", minimal_manifest()), tar_file("big.bin", std::string(10000, 'z'))});
  write(tar.substr(0, 1024 + 512 + 3000));  // cut inside big.bin's data
  try {
    check_mission_bundle(path_);
    ADD_FAILURE() << "truncated tar accepted";
  } catch (const BundleError& e) {
    EXPECT_EQ(e.code(), "bad_bundle");
  }
}

TEST_F(BundleCheckTest, RefusesTooManyMembersBeforeReadingTheRest) {
  std::vector<TarMember> members = {tar_file("mission.yaml", minimal_manifest())};
  for (int i = 0; i < 10; ++i) members.push_back(tar_file("f" + std::to_string(i), "x"));
  write(build_tar(members));
  BundleLimits limits;
  limits.max_members = 11;
  EXPECT_EQ(check_mission_bundle(path_, limits).members, 11);
  limits.max_members = 10;
  try {
    check_mission_bundle(path_, limits);
    ADD_FAILURE() << "11 members accepted with a limit of 10";
  } catch (const BundleError& e) {
    EXPECT_EQ(e.code(), "bad_bundle");
    EXPECT_STREQ(e.what(), "bundle has more than 10 members (the limit)");
  }
}

TEST_F(BundleCheckTest, RefusesMembersNestedDeeperThanTheLimit) {
  std::string deep;
  for (int i = 0; i < 63; ++i) deep += "d/";
  // 63 folders and a file: 64 components, the limit.
  write(build_tar({tar_file("mission.yaml", minimal_manifest()), tar_file(deep + "f", "x")}));
  EXPECT_EQ(check_mission_bundle(path_).members, 2);
  auto [code, message] =
      reject({tar_file("mission.yaml", minimal_manifest()), tar_file(deep + "d/f", "x")});
  EXPECT_EQ(code, "bad_bundle");
  EXPECT_NE(message.find("is nested 65 folders deep (limit 64)"), std::string::npos) << message;
}

// GNU tar stores a 1 GiB hole in a few kilobytes: a sparse member that would unpack to far
// more than was uploaded is refused.
TEST_F(BundleCheckTest, RefusesSparseMembersThatUnpackToMoreThanTheBundle) {
  const auto dir = std::filesystem::path(path_).replace_extension(".d");
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "mission.yaml") << minimal_manifest();
  { std::ofstream(dir / "hole.bin"); }
  std::filesystem::resize_file(dir / "hole.bin", int64_t{1} << 30);
  const std::string command = "tar --sparse -C '" + dir.string() + "' -cf '" + path_.string() +
                              "' mission.yaml hole.bin 2>&1";
  const int status = std::system(command.c_str());
  std::filesystem::remove_all(dir);
  if (status != 0) GTEST_SKIP() << "no GNU tar with --sparse here";
  ASSERT_LT(std::filesystem::file_size(path_), 1u << 20) << "tar did not store a sparse member";
  try {
    check_mission_bundle(path_);
    ADD_FAILURE() << "a 1 GiB sparse member was accepted";
  } catch (const BundleError& e) {
    EXPECT_EQ(e.code(), "bad_bundle");
    const std::string total = std::to_string((int64_t{1} << 30) + minimal_manifest().size());
    EXPECT_NE(std::string(e.what()).find("member 'hole.bin' makes the files add up to " + total +
                                         " bytes, more than the " +
                                         std::to_string(std::filesystem::file_size(path_)) +
                                         "-byte bundle holds"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace keel::server
