// GET /v1/artifacts/{id}/files/{path}: one member of a tar artifact (the map tiles) served as
// a region of the stored tar, with Range, ETag and 304 as any artifact; a path that is not a
// member, an artifact that is not a tar, a pax tar and a truncated one answer 404 naming what
// is wrong, and the tars GNU tar writes (the reference tool) are read as libarchive's are.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "server/tar_index.h"
#include "tests/server/handler_fixture.h"

namespace keel::server::testing {
namespace {

class ArtifactFilesTest : public HandlerTest {
 protected:
  void SetUp() override {
    HandlerTest::SetUp();
    auto mission = create_mission("m1");
    job_id_ = create_job(mission["id"], {"ingest", "map"})["id"];
    lease_id_ = lease()["lease_id"];
  }

  std::string add_artifact(const std::string& name, const std::string& bytes) {
    const std::string blob = upload(bytes, 1 << 20);
    Response registered =
        post("/v1/worker/jobs/" + job_id_ + "/artifacts",
             {{"lease_id", lease_id_}, {"stage", "map"}, {"name", name}, {"blob", blob}});
    EXPECT_EQ(registered.status, 201) << registered.body;
    return json_of(registered)["id"];
  }

  Response get(const std::string& target, const std::map<std::string, std::string>& headers = {}) {
    return call("GET", target, "", headers);
  }

  std::string job_id_, lease_id_;
};

TEST_F(ArtifactFilesTest, MembersAreServedWithRangesAndETags) {
  const std::string tileset = R"({"asset": {"version": "1.0"}})";
  const std::string tile = random_bytes(5000, 3), deep = random_bytes(700, 4);
  const std::string id = add_artifact(
      "tiles_lidar.tar", build_tar({tar_file("tileset.json", tileset), tar_file("r.pnts", tile),
                                    tar_dir("sub"), tar_file("sub/r01.pnts", deep)},
                                   false, ARCHIVE_FORMAT_TAR_USTAR));
  const std::string base = "/v1/artifacts/" + id + "/files/";

  Response json = get(base + "tileset.json");
  ASSERT_EQ(json.status, 200) << json.body;
  ASSERT_TRUE(json.file.has_value());
  EXPECT_EQ(read_region(*json.file), tileset);
  EXPECT_EQ(json.headers.get("Content-Type"), "application/json");
  EXPECT_EQ(json.headers.get("Accept-Ranges"), "bytes");

  Response nested = get(base + "sub/r01.pnts");
  ASSERT_EQ(nested.status, 200);
  EXPECT_EQ(read_region(*nested.file), deep);

  Response part = get(base + "r.pnts", {{"Range", "bytes=100-1099"}});
  ASSERT_EQ(part.status, 206);
  EXPECT_EQ(read_region(*part.file), tile.substr(100, 1000));
  EXPECT_EQ(part.headers.get("Content-Range"), "bytes 100-1099/5000");
  EXPECT_EQ(get(base + "r.pnts", {{"Range", "bytes=5000-"}}).status, 416);

  const auto etag = get(base + "r.pnts").headers.get("ETag");
  ASSERT_TRUE(etag.has_value());
  EXPECT_NE(*etag, *json.headers.get("ETag"));  // one tag per member
  EXPECT_EQ(get(base + "r.pnts", {{"If-None-Match", *etag}}).status, 304);

  Response missing = get(base + "r7.pnts");
  EXPECT_EQ(missing.status, 404);
  EXPECT_NE(missing.body.find("no member 'r7.pnts'"), std::string::npos) << missing.body;
  EXPECT_EQ(get(base + "sub").status, 404);  // a folder is not a file
  EXPECT_EQ(get("/v1/artifacts/unknown/files/tileset.json").status, 404);
  EXPECT_EQ(call("GET", base + "tileset.json", "", {}, false).status, 401);
}

TEST_F(ArtifactFilesTest, WhatIsNotAUstarTarIsRefusedByName) {
  const std::string plain = add_artifact("report.json", random_bytes(3000, 5));
  Response not_tar = get("/v1/artifacts/" + plain + "/files/x");
  EXPECT_EQ(not_tar.status, 404);
  EXPECT_NE(not_tar.body.find("artifact 'report.json'"), std::string::npos) << not_tar.body;

  const std::string long_name(150, 'a');
  const std::string pax = add_artifact(
      "pax.tar",
      build_tar({tar_file(long_name + ".pnts", "x")}, false, ARCHIVE_FORMAT_TAR_PAX_RESTRICTED));
  Response refused = get("/v1/artifacts/" + pax + "/files/" + long_name + ".pnts");
  EXPECT_EQ(refused.status, 404);
  EXPECT_NE(refused.body.find("pax"), std::string::npos) << refused.body;

  std::string cut =
      build_tar({tar_file("a.pnts", random_bytes(4000, 6))}, false, ARCHIVE_FORMAT_TAR_USTAR);
  cut.resize(2000);  // the member's data stops short
  const std::string truncated = add_artifact("cut.tar", cut);
  Response short_tar = get("/v1/artifacts/" + truncated + "/files/a.pnts");
  EXPECT_EQ(short_tar.status, 404);
  EXPECT_NE(short_tar.body.find("past the end"), std::string::npos) << short_tar.body;
}

TEST_F(ArtifactFilesTest, AnotherProjectsTarAnswers404AndItsOwnViewerReadsIt) {
  const std::string id =
      add_artifact("tiles_lidar.tar",
                   build_tar({tar_file("tileset.json", "{}")}, false, ARCHIVE_FORMAT_TAR_USTAR));
  const std::string target = "/v1/artifacts/" + id + "/files/tileset.json";
  const auto as = [&](proto::Role role, const std::string& project) {
    storage::TokenSpec spec;
    spec.role = role;
    spec.project = project;
    const std::string token = "tok-" + project;
    store_->add_token(token, spec);
    return call("GET", target, "", {{"Authorization", "Bearer " + token}}, false);
  };
  Response stranger = as(proto::Role::kAdmin, "dock");  // even an admin of another project
  EXPECT_EQ(stranger.status, 404) << stranger.body;
  EXPECT_EQ(stranger.body.find("tiles_lidar"), std::string::npos) << stranger.body;
  Response viewer = as(proto::Role::kViewer, proto::kDefaultProject);
  ASSERT_EQ(viewer.status, 200) << viewer.body;
  EXPECT_EQ(read_region(*viewer.file), "{}");
}

TEST(TarIndex, ReadsWhatGnuTarWrites) {
  TempDir dir;
  const auto root = dir.path() / "in";
  std::filesystem::create_directories(root / "deep/er");
  const std::string a = random_bytes(1234, 8), b = random_bytes(512, 9);
  std::ofstream(root / "a.pnts", std::ios::binary) << a;
  std::ofstream(root / "deep/er/b.json", std::ios::binary) << b;
  const auto tar = dir.path() / "t.tar";
  const std::string command =
      "tar --format=ustar -cf '" + tar.string() + "' -C '" + root.string() + "' .";
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  const TarIndex index = read_tar_index(tar, std::filesystem::file_size(tar), "t.tar");
  ASSERT_TRUE(index.count("a.pnts"));
  ASSERT_TRUE(index.count("deep/er/b.json"));
  std::ifstream in(tar, std::ios::binary);
  std::stringstream bytes;
  bytes << in.rdbuf();
  const std::string all = bytes.str();
  EXPECT_EQ(all.substr(index.at("a.pnts").offset, index.at("a.pnts").size), a);
  EXPECT_EQ(all.substr(index.at("deep/er/b.json").offset, index.at("deep/er/b.json").size), b);
  EXPECT_EQ(index.size(), 2u);  // folders are not members to serve
}

}  // namespace
}  // namespace keel::server::testing
