// The dashboard's static files through the pure handler: MIME types, cache headers, the
// Content-Security-Policy with the import map's hash, and every way out of the web folder
// refused.
#include <gtest/gtest.h>

#include <fstream>

#include "server/static_files.h"
#include "tests/server/handler_fixture.h"

namespace keel::server::testing {
namespace {

namespace fs = std::filesystem;

void write(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary) << text;
}

// Published SHA-256 test vector (FIPS 180-2, "abc"), in base64.
TEST(InlineScriptHashes, MatchTheFips180VectorInBase64) {
  const auto hashes = inline_script_hashes(
      "<p><script type=\"importmap\">abc</script>"
      "<script type=\"module\" src=\"./m.js\"></script>");
  ASSERT_EQ(hashes.size(), 1u);
  EXPECT_EQ(hashes[0], "'sha256-ungWv48Bz+pBQUDeXa4iI7ADYaOWF3qctBD/YfIAFa0='");
}

TEST(MimeTypes, ModulesWasmAndUnknown) {
  EXPECT_EQ(mime_type_for_extension("js"), "text/javascript; charset=utf-8");
  EXPECT_EQ(mime_type_for_extension("JS"), "text/javascript; charset=utf-8");
  EXPECT_EQ(mime_type_for_extension("wasm"), "application/wasm");
  EXPECT_EQ(mime_type_for_extension("css"), "text/css; charset=utf-8");
  EXPECT_EQ(mime_type_for_extension("html"), "text/html; charset=utf-8");
  EXPECT_EQ(mime_type_for_extension("exe"), "application/octet-stream");
}

class StaticFilesTest : public HandlerTest {
 protected:
  void SetUp() override {
    HandlerTest::SetUp();
    web_ = dir_.path() / "web";
    write(web_ / "index.html",
          "<html><script type=\"importmap\">{\"imports\":{}}</script>"
          "<script type=\"module\" src=\"./js/main.js\"></script></html>");
    write(web_ / "js" / "main.js", "export const x = 1;\n");
    write(web_ / "vendor" / "three-0.187.0" / "draco_decoder.wasm", std::string("\0asm", 4));
    write(web_ / ".hidden", "secret");
    write(dir_.path() / "outside.txt", "outside");
    fs::create_symlink(dir_.path() / "outside.txt", web_ / "link.txt");
    HandlerOptions options;
    options.web = std::make_shared<StaticFiles>(web_);
    handler_ = std::make_unique<HttpHandler>(*store_, options);
  }

  Response get(const std::string& target, const std::map<std::string, std::string>& headers = {}) {
    return call("GET", target, "", headers, /*with_token=*/false);
  }

  fs::path web_;
};

TEST_F(StaticFilesTest, RootIsIndexHtmlWithNoCacheAndTheImportMapHashInTheCsp) {
  const Response r = get("/");
  ASSERT_EQ(r.status, 200) << r.body;
  EXPECT_EQ(r.headers.get("Content-Type"), "text/html; charset=utf-8");
  EXPECT_EQ(r.headers.get("Cache-Control"), "no-cache");
  EXPECT_NE(r.body.find("importmap"), std::string::npos);
  const std::string csp = r.headers.get("Content-Security-Policy").value_or("");
  const auto hashes = inline_script_hashes(r.body);
  ASSERT_EQ(hashes.size(), 1u);
  EXPECT_NE(csp.find("script-src 'self' 'wasm-unsafe-eval' " + hashes[0]), std::string::npos)
      << csp;
  EXPECT_NE(csp.find("default-src 'none'"), std::string::npos);
  EXPECT_NE(csp.find("worker-src blob:"), std::string::npos);
  EXPECT_NE(csp.find("connect-src 'self'"), std::string::npos);
  EXPECT_EQ(csp.find("http"), std::string::npos) << "no external source: " << csp;
  EXPECT_EQ(csp.find("unsafe-inline"), std::string::npos);
  EXPECT_EQ(r.headers.get("X-Content-Type-Options"), "nosniff");
}

TEST_F(StaticFilesTest, ModulesAreJavascriptAndRevalidatedWithTheirEtag) {
  const Response r = get("/js/main.js");
  ASSERT_EQ(r.status, 200);
  EXPECT_EQ(r.headers.get("Content-Type"), "text/javascript; charset=utf-8");
  EXPECT_EQ(r.headers.get("Cache-Control"), "no-cache");
  ASSERT_TRUE(r.file);
  EXPECT_EQ(read_region(*r.file), "export const x = 1;\n");
  const std::string etag = r.headers.get("ETag").value_or("");
  ASSERT_FALSE(etag.empty());
  const Response again = get("/js/main.js", {{"If-None-Match", etag}});
  EXPECT_EQ(again.status, 304);
  EXPECT_FALSE(again.file);
}

TEST_F(StaticFilesTest, VendoredFilesAreImmutableAndWasmHasItsType) {
  const Response r = get("/vendor/three-0.187.0/draco_decoder.wasm");
  ASSERT_EQ(r.status, 200);
  EXPECT_EQ(r.headers.get("Content-Type"), "application/wasm");
  EXPECT_EQ(r.headers.get("Cache-Control"), "public, max-age=31536000, immutable");
}

TEST_F(StaticFilesTest, PathsOutOfTheFolderAreRefused) {
  for (const std::string target :
       {"/../outside.txt", "/js/../../outside.txt", "/%2e%2e/outside.txt",
        "/js/%2e%2e%2f%2e%2e%2foutside.txt", "/js%2f..%2f..%2foutside.txt", "/./index.html",
        "/js/..%5c..%5coutside.txt", "/a%00b"}) {
    const Response r = get(target);
    EXPECT_EQ(r.status, 400) << target;
    EXPECT_EQ(error_code_of(r), "unsafe_path") << target;
    EXPECT_FALSE(r.file) << target;
  }
  // A symlink inside the folder that leads out of it, a dot file, a folder, a missing file.
  for (const std::string target : {"/link.txt", "/.hidden", "/js", "/nothing.js"}) {
    const Response r = get(target);
    EXPECT_EQ(r.status, 404) << target;
    EXPECT_FALSE(r.file) << target;
  }
}

TEST_F(StaticFilesTest, ApiRoutesStillNeedTheirTokenAndKeepTheirAnswers) {
  EXPECT_EQ(get("/v1/jobs").status, 401);
  EXPECT_EQ(get("/v1/index.html").status, 401);
  EXPECT_EQ(get("/healthz").status, 200);
  EXPECT_EQ(call("POST", "/", "{}", {}, false).status, 404);
}

TEST_F(StaticFilesTest, AMissingWebFolderAnswers404NamingIt) {
  HandlerOptions options;
  options.web = std::make_shared<StaticFiles>(dir_.path() / "no-such-folder");
  handler_ = std::make_unique<HttpHandler>(*store_, options);
  const Response r = get("/");
  EXPECT_EQ(r.status, 404);
  EXPECT_NE(r.body.find("no-such-folder"), std::string::npos) << r.body;
}

}  // namespace
}  // namespace keel::server::testing
