// POST/GET /v1/missions through the pure handler, including hostile bundle tars.
#include "tests/server/handler_fixture.h"

namespace keel::server::testing {
namespace {

class MissionRoutesTest : public HandlerTest {
 protected:
  Response create_from_tar(const std::string& tar, const std::string& name = "m1") {
    return post("/v1/missions", {{"name", name}, {"bundle_blob", upload(tar)}});
  }
};

TEST_F(MissionRoutesTest, CreateGetAndListByPrefix) {
  auto a = create_mission("bridge-a");
  auto b = create_mission("bridge-b");
  auto c = create_mission("hull-c");
  EXPECT_EQ(a["name"], "bridge-a");

  Response got = call("GET", "/v1/missions/" + b["id"].get<std::string>());
  ASSERT_EQ(got.status, 200);
  EXPECT_EQ(json_of(got), b);

  auto all = json_of(call("GET", "/v1/missions"))["missions"];
  EXPECT_EQ(all.size(), 3u);
  auto bridges = json_of(call("GET", "/v1/missions?prefix=bridge-"))["missions"];
  ASSERT_EQ(bridges.size(), 2u);
  for (const auto& mission : bridges)
    EXPECT_EQ(mission["name"].get<std::string>().rfind("bridge-", 0), 0u);
  // Percent-encoded query values are decoded.
  EXPECT_EQ(json_of(call("GET", "/v1/missions?prefix=hull%2Dc"))["missions"].size(), 1u);
  EXPECT_EQ(call("GET", "/v1/missions/nope").status, 404);
}

TEST_F(MissionRoutesTest, MissingBlobsGive404AndBadShaGives400) {
  const std::string absent = keel::sha256_bytes("never uploaded");
  Response response = post("/v1/missions", {{"name", "m"}, {"bundle_blob", absent}});
  EXPECT_EQ(response.status, 404);
  EXPECT_NE(response.body.find("bundle_blob"), std::string::npos);

  Response bad = post("/v1/missions", {{"name", "m"}, {"bundle_blob", "xyz"}});
  EXPECT_EQ(bad.status, 400);
  EXPECT_EQ(error_code_of(bad), "invalid_field");
}

TEST_F(MissionRoutesTest, DotDotMemberGivesUnsafePathNamingIt) {
  Response response = create_from_tar(
      build_tar({tar_file("mission.yaml", minimal_manifest()), tar_file("../x", "evil")}));
  EXPECT_EQ(response.status, 400);
  EXPECT_EQ(error_code_of(response), "unsafe_path");
  EXPECT_NE(response.body.find("../x"), std::string::npos) << response.body;
  EXPECT_EQ(store_->metrics().missions, 0);
}

TEST_F(MissionRoutesTest, AbsoluteMemberGivesUnsafePath) {
  Response response = create_from_tar(build_tar(
      {tar_file("mission.yaml", minimal_manifest()), tar_file("/etc/passwd", "root:x:0:0")}));
  EXPECT_EQ(response.status, 400);
  EXPECT_EQ(error_code_of(response), "unsafe_path");
  EXPECT_NE(response.body.find("/etc/passwd"), std::string::npos) << response.body;
}

TEST_F(MissionRoutesTest, EscapingSymlinkGivesUnsafePath) {
  Response response = create_from_tar(
      build_tar({tar_file("mission.yaml", minimal_manifest()), tar_symlink("data", "/var/lib")}));
  EXPECT_EQ(response.status, 400);
  EXPECT_EQ(error_code_of(response), "unsafe_path");
}

TEST_F(MissionRoutesTest, NotATarOrNoManifestGivesBadBundle) {
  Response text = create_from_tar("plain text, not a tar archive; plain text, not a tar archive");
  EXPECT_EQ(text.status, 400);
  EXPECT_EQ(error_code_of(text), "bad_bundle");
  Response empty_tar = create_from_tar(build_tar({tar_file("readme.txt", "hi")}));
  EXPECT_EQ(empty_tar.status, 400);
  EXPECT_EQ(error_code_of(empty_tar), "bad_bundle");
  EXPECT_NE(empty_tar.body.find("mission.yaml"), std::string::npos);
}

}  // namespace
}  // namespace keel::server::testing
