#include "worker/pipeline/report.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <sstream>

namespace keel::pipeline {
namespace {

namespace fs = std::filesystem;

ReportInput sample_input() {
  ReportInput in;
  in.job = {{"id", "j1"}, {"stages", {"refine", "ingest"}}};
  in.mission = {{"id", "m1"}, {"name", "usv-bridge"}};
  in.stage_order = {"refine", "ingest"};  // deliberately not alphabetical
  in.stages = {{"ingest", {{"imu_rate_hz", 200.0}}}, {"refine", {{"ate_m", 0.12}}}};
  in.stage_seconds = {{"ingest", 0.5}, {"refine", 3.25}};
  return in;
}

TEST(ReportTest, AssemblesSectionsInStageOrder) {
  const nlohmann::ordered_json report = build_report(sample_input());

  EXPECT_EQ(report["keel_report"], 1);
  EXPECT_EQ(report["job"]["id"], "j1");
  EXPECT_EQ(report["mission"]["name"], "usv-bridge");
  EXPECT_DOUBLE_EQ(report["stages"]["ingest"]["imu_rate_hz"].get<double>(), 200.0);
  EXPECT_DOUBLE_EQ(report["stages"]["refine"]["ate_m"].get<double>(), 0.12);
  EXPECT_DOUBLE_EQ(report["stage_seconds"]["refine"].get<double>(), 3.25);

  std::vector<std::string> top, stages;
  for (const auto& item : report.items()) top.push_back(item.key());
  for (const auto& item : report["stages"].items()) stages.push_back(item.key());
  EXPECT_EQ(top,
            (std::vector<std::string>{"keel_report", "job", "mission", "stages", "stage_seconds"}));
  EXPECT_EQ(stages, (std::vector<std::string>{"refine", "ingest"}));
}

TEST(ReportTest, MissingSectionIsAnErrorNamingTheStage) {
  ReportInput in = sample_input();
  in.stages.erase("refine");
  try {
    build_report(in);
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'refine' has no section"), std::string::npos) << e.what();
  }
}

TEST(ReportTest, SectionOfAStageOutsideTheJobIsAnError) {
  ReportInput in = sample_input();
  in.stages["map"] = nlohmann::json::object();
  EXPECT_THROW(build_report(in), std::invalid_argument);
  in = sample_input();
  in.stage_seconds["map"] = 1.0;
  EXPECT_THROW(build_report(in), std::invalid_argument);
}

TEST(ReportTest, NonObjectSectionIsAnError) {
  ReportInput in = sample_input();
  in.stages["ingest"] = 42;
  EXPECT_THROW(build_report(in), std::invalid_argument);
}

TEST(ReportTest, WritesAtomicallyAndReplacesAnOldReport) {
  const fs::path dir = fs::temp_directory_path() / ("keel_report_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path path = dir / kReportFileName;
  std::ofstream(path) << "old";

  const auto report = build_report(sample_input());
  write_json_atomically(path, report);

  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(nlohmann::ordered_json::parse(text.str()), report);
  // Only the report remains: the temporary file was renamed, not left behind.
  int files = 0;
  for (const auto& item : fs::directory_iterator(dir)) {
    (void)item;
    ++files;
  }
  EXPECT_EQ(files, 1);
  fs::remove_all(dir);
}

TEST(ReportTest, WriteIntoMissingFolderNamesTheFile) {
  const fs::path path = fs::temp_directory_path() / "keel_no_such_folder_xyz" / "report.json";
  try {
    write_json_atomically(path, build_report(sample_input()));
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("keel_no_such_folder_xyz"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace keel::pipeline
