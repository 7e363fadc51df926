// report.html on hand-made reports: numbers are printed exactly as report.json holds them (the
// text reads back as the same double), hostile strings are escaped, and the page passes
// report_html_check.py (a real XML and HTML parse with Debian's Python: every figure present
// with its value, nothing to fetch or run), also for a failed job and for stages with figures
// missing. Real stage reports are checked by report_artifacts_test.
#include "worker/pipeline/report_html.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <random>

#include "worker/pipeline/html_text.h"
#include "worker/pipeline/report.h"

namespace keel::pipeline {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using nlohmann::ordered_json;

TEST(HtmlText, ExactNumbersReadBackAsTheSameDouble) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> mantissa(-1.0, 1.0);
  std::uniform_int_distribution<int> exponent(-300, 300);
  for (int i = 0; i < 20000; ++i) {
    const double v = std::ldexp(mantissa(rng), exponent(rng));
    const std::string text = html::format_exact(json(v));
    EXPECT_EQ(std::strtod(text.c_str(), nullptr), v) << text;
  }
  EXPECT_EQ(html::format_exact(json(12345678901234LL)), "12345678901234");
  EXPECT_EQ(html::format_exact(json(std::nan(""))), "null");
  EXPECT_THROW(html::format_exact(json("1")), std::invalid_argument);
}

TEST(HtmlText, ShownNumbersAreRoundedForReading) {
  EXPECT_EQ(html::format_shown(0.0134276), "0.01343");
  EXPECT_EQ(html::format_shown(31986.9), "31987");
  EXPECT_EQ(html::format_shown(1.5e-5), "1.500e-05");
  EXPECT_EQ(html::format_shown(-2.5), "-2.500");
  EXPECT_EQ(html::format_shown(12.0), "12");
  EXPECT_EQ(html::format_shown(std::numeric_limits<double>::infinity()), "null");
  EXPECT_EQ(html::data(json(0.5), "/a/b", "m"),
            "<data value=\"0.5\" data-pointer=\"/a/b\">0.5000 m</data>");
}

TEST(HtmlText, EscapesMarkupQuotesAndControlCharacters) {
  EXPECT_EQ(html::escape("<script>alert(\"x\") & 'y'</script>\x01"),
            "&lt;script&gt;alert(&quot;x&quot;) &amp; &#39;y&#39;&lt;/script&gt;&#xFFFD;");
  EXPECT_EQ(html::pointer_token("a/b~c"), "a~1b~0c");
}

// Runs report_html_check.py on the files; returns its exit code (-1: no Debian Python).
int check(const fs::path& report_json, const fs::path& report_html, const std::string& extra = "") {
  if (!fs::exists("/usr/bin/python3")) return -1;
  const std::string command = "/usr/bin/python3 " KEEL_SOURCE_DIR
                              "/tests/worker/pipeline/report_html_check.py '" +
                              report_json.string() + "' '" + report_html.string() + "' " + extra;
  return WEXITSTATUS(std::system(command.c_str()));
}

class ReportHtmlTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("keel_report_html_" + std::to_string(getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string read(const fs::path& path) {
    std::ifstream in(path);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }
  fs::path dir_;
};

TEST_F(ReportHtmlTest, HostileStringsAndOddFiguresPassTheCheck) {
  ReportInput in;
  in.job = {{"id", "j_<b>&1"}, {"stages", {"ingest", "refine", "map", "ba", "inspect"}}};
  in.mission = {{"name", "<script>alert('x')</script> & \"pier\""}};
  in.stage_order = {"ingest", "refine", "map", "ba", "inspect"};
  json odd = {{"key/with~slash", 1.0 / 3.0},
              {"nan", std::nan("")},
              {"big", 1.7976931348623157e308},
              {"tiny", 4.9406564584124654e-324},
              {"negative_zero", -0.0},
              {"integer", -9007199254740993LL},
              {"nested", {{1, 2.5}, {json::array(), json::object()}}},
              {"text", "line1\nline2 </td></tr><script>"},
              {"url", "see h\u0074tp-less text only"},
              {"flag", true},
              {"nothing", nullptr}};
  in.stages = {{"ingest", odd},
               {"refine", {{"evaluation", nullptr}, {"dvl", nullptr}}},
               {"map", json::object()},
               {"ba", {{"modes", {{"proposed", {{"cost_per_iteration", {3.0, 2.0, 1.0}}}}}}}},
               {"inspect", {{"shapes", json::array()}}}};
  in.stage_seconds = {{"ingest", 0.25}};
  const ordered_json report = build_report(in);
  const auto files = write_report_files(dir_, report);
  ASSERT_EQ(files, (std::vector<std::string>{"report.json", "report.html"}));
  const std::string page = read(dir_ / "report.html");
  EXPECT_EQ(page.find("<script"), std::string::npos);
  EXPECT_NE(page.find("&lt;script&gt;alert"), std::string::npos);
  const int code = check(dir_ / "report.json", dir_ / "report.html",
                         "--expect /stage_seconds/ingest --expect-id stage-ba");
  if (code == -1) GTEST_SKIP() << "no /usr/bin/python3";
  EXPECT_EQ(code, 0);
}

TEST_F(ReportHtmlTest, FailedJobShowsTheErrorFirst) {
  ReportInput in;
  in.job = {{"id", "j_2"}, {"stages", {"ingest", "map"}}};
  in.stage_order = {"ingest"};
  in.stages = {{"ingest", {{"loop_closures", 0}}}};
  in.failure = {{"stage", "map"}, {"error", "map: scans/0001.pcd: truncated <here>"}};
  write_report_files(dir_, build_report(in));
  const std::string page = read(dir_ / "report.html");
  const size_t failure = page.find("id=\"failure\"");
  ASSERT_NE(failure, std::string::npos);
  EXPECT_LT(failure, page.find("id=\"stage-ingest\""));
  EXPECT_NE(page.find("truncated &lt;here&gt;"), std::string::npos);
  const int code = check(dir_ / "report.json", dir_ / "report.html", "--expect-id failure");
  if (code == -1) GTEST_SKIP() << "no /usr/bin/python3";
  EXPECT_EQ(code, 0);
}

TEST_F(ReportHtmlTest, TheCheckCatchesAWrongFigureAndAnExternalReference) {
  ReportInput in;
  in.job = {{"id", "j_3"}, {"stages", {"ingest"}}};
  in.stage_order = {"ingest"};
  in.stages = {{"ingest", {{"loop_closures", 0}, {"rate", 0.1}}}};
  write_report_files(dir_, build_report(in));
  std::string page = read(dir_ / "report.html");
  // The checker itself must fail on a changed value and on a fetched resource.
  const std::string good = "<data value=\"0.1\" data-pointer=\"/stages/ingest/rate\">";
  ASSERT_NE(page.find(good), std::string::npos);
  std::string wrong = page;
  wrong.replace(wrong.find(good), good.size(),
                "<data value=\"0.10000000000000002\" data-pointer=\"/stages/ingest/rate\">");
  std::ofstream(dir_ / "wrong.html") << wrong;
  std::string fetching = page;
  fetching.insert(fetching.find("</body>"), "<img src=\"https://example.com/x.png\"/>");
  std::ofstream(dir_ / "fetching.html") << fetching;
  const int code = check(dir_ / "report.json", dir_ / "wrong.html");
  if (code == -1) GTEST_SKIP() << "no /usr/bin/python3";
  EXPECT_EQ(code, 1);
  EXPECT_EQ(check(dir_ / "report.json", dir_ / "fetching.html"), 1);
  EXPECT_EQ(check(dir_ / "report.json", dir_ / "report.html"), 0);
}

}  // namespace
}  // namespace keel::pipeline
