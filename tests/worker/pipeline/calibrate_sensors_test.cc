// The calibrate stage's choice of sensors and its errors, and its files on a short keel-sim
// mission: the options' messages name the option and the sensor; a mission with one range
// sensor has nothing to calibrate (not an error, so a job of every stage still runs); the
// files follow docs/calibration.md.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "proto/contract_error.h"
#include "tests/worker/pipeline/sim_mission.h"
#include "tests/worker/pipeline/stage_run.h"
#include "worker/pipeline/report_html_parts.h"
#include "worker/pipeline/stage.h"
#include "worker/stages/calibrate/artifacts.h"

namespace keel::pipeline {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

fs::path root() {
  static const fs::path dir = [] {
    const fs::path d = fs::temp_directory_path() / "keel-calibrate-sensors";
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
  }();
  return dir;
}

const fs::path& two_lidars() {
  static const fs::path dir =
      testing::simulate(root() / "two", "usv-bridge", 5, 15.0, {"lidar_h", "lidar_v"});
  return dir;
}

std::string error_of(const json& options) {
  auto stage = make_stage("calibrate");
  try {
    testing::run_stage(*stage, two_lidars(), options, root() / "err");
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(CalibrateSensors, OptionsNamingWrongSensorsAreRefusedNamingThem) {
  EXPECT_EQ(error_of({{"candidates", "sonr"}}),
            "options.calibrate.candidates: mission has no sensor 'sonr' (it has: lidar_h, "
            "lidar_v)");
  EXPECT_EQ(error_of({{"reference", "lidar_v"}, {"candidates", {"lidar_v"}}}),
            "options.calibrate.candidates: 'lidar_v' is the reference sensor");
  EXPECT_NE(error_of({{"final_correspondence_m", 2.0}}).find("max_correspondence_m"),
            std::string::npos);
}

TEST(CalibrateSensors, OneRangeSensorIsNothingToCalibrate) {
  const fs::path mission = testing::simulate(root() / "one", "usv-bridge", 5, 3.0, {"lidar_h"});
  auto stage = make_stage("calibrate");
  const StageResult result =
      testing::run_stage(*stage, mission, json::object(), root() / "one_work").result;
  EXPECT_TRUE(result.artifacts.empty());
  EXPECT_NE(result.report["nothing_to_calibrate"].get<std::string>().find("lidar_h"),
            std::string::npos);
}

TEST(CalibrateSensors, FilesFollowTheContract) {
  const fs::path work = root() / "files";
  auto stage = make_stage("calibrate");
  const StageResult result = testing::run_stage(*stage, two_lidars(), json::object(), work).result;
  const json calibration = json::parse(std::ifstream(work / kCalibrationFile));
  EXPECT_EQ(calibration["reference"], "lidar_h");
  ASSERT_EQ(calibration["candidates"].size(), 1u);
  const json& c = calibration["candidates"][0];
  EXPECT_EQ(c["sensor"], "lidar_v");
  ASSERT_EQ(c["status"], "refined") << c.value("reason", "");
  // The override offered is the refined extrinsic, under T_<reference>_<candidate>.
  EXPECT_EQ(c["reprocess"]["options"]["calibration"]["lidar_v"]["T_lidar_h_lidar_v"],
            c["refined"]["T_reference_candidate"]);
  const std::string set = c["reprocess"]["set"][0];
  const std::string prefix = "calibration.lidar_v.T_lidar_h_lidar_v=";
  ASSERT_EQ(set.rfind(prefix, 0), 0u) << set;
  EXPECT_EQ(json::parse(set.substr(prefix.size())), c["refined"]["T_reference_candidate"]);
  EXPECT_EQ(c["covariance"].size(), 6u);
  const CalibrationScans scans = read_calibration_scans(work / kCalibrationScansFile);
  EXPECT_EQ(scans.reference, "lidar_h");
  ASSERT_EQ(scans.sensors.size(), 2u);
  EXPECT_EQ(scans.sensors[0].source, "mission.yaml");
  const report_html::Json section = result.report;
  const std::string html = stage->report_html(report_html::Ref(section, "/calibrate"), {});
  EXPECT_NE(html.find("keel reprocess"), std::string::npos);
  EXPECT_NE(html.find("T_reference_lidar_v"), std::string::npos);
  // Every cell of the quality table reads a value of the report (none is a dash).
  const size_t quality = html.find("calibrate-lidar_v-quality");
  ASSERT_NE(quality, std::string::npos);
  EXPECT_EQ(html.substr(quality, html.find("</table>", quality) - quality).find("&#8212;"),
            std::string::npos)
      << html.substr(quality);
}

}  // namespace
}  // namespace keel::pipeline
