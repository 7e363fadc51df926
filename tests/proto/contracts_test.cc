#include <gtest/gtest.h>

#include "proto/api_error.h"
#include "proto/contract_error.h"
#include "proto/job.h"
#include "proto/options.h"
#include "proto/resources.h"
#include "proto/worker_protocol.h"

namespace keel::proto {
namespace {

const std::string kSha(64, 'a');

// Expects a ContractError whose message contains `needle` (the field path).
template <typename F>
void expect_contract_error(F&& f, const std::string& needle) {
  try {
    f();
    FAIL() << "expected ContractError mentioning '" << needle << "'";
  } catch (const ContractError& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST(Contracts, JobRoundTripKeepsEveryField) {
  Job job;
  job.id = "j_1";
  job.mission_id = "m_1";
  job.state = JobState::kRunning;
  job.stages = {"ingest", "refine"};
  job.options = {{"refine", {{"dvl", false}}}};
  job.stage = "refine";
  job.progress = 0.25;
  job.completed_stages = {"ingest"};
  job.stage_seconds = {{"ingest", 1.5}};
  job.attempts = 2;
  job.created_at_ms = 10;
  job.started_at_ms = 20;
  const Job back = Job::from_json(nlohmann::json::parse(job.to_json().dump()));
  EXPECT_EQ(back.to_json(), job.to_json());
  EXPECT_EQ(back.state, JobState::kRunning);
  EXPECT_DOUBLE_EQ(back.stage_seconds.at("ingest"), 1.5);
}

TEST(Contracts, JobStateNamesRoundTrip) {
  for (auto s : {JobState::kQueued, JobState::kRunning, JobState::kSucceeded, JobState::kFailed,
                 JobState::kCanceled})
    EXPECT_EQ(job_state_from_string(to_string(s)), s);
  expect_contract_error([] { job_state_from_string("paused", "jobs[3].state"); }, "jobs[3].state");
}

TEST(Contracts, JobRequestErrorsNameTheField) {
  expect_contract_error([] { JobRequest::from_json({{"stages", {"ingest"}}}); }, "mission_id: missing");
  expect_contract_error([] { JobRequest::from_json({{"mission_id", 3}, {"stages", {"ingest"}}}); },
                        "mission_id: expected string, got integer");
  expect_contract_error(
      [] { JobRequest::from_json({{"mission_id", "m"}, {"stages", {"ingest"}}, {"colour", 1}}); },
      "colour: unknown field");
  expect_contract_error([] { JobRequest::from_json({{"mission_id", "m"}, {"stages", {"ingest", "fly"}}}); },
                        "stages[1]: unknown stage 'fly'");
  expect_contract_error([] { JobRequest::from_json({{"mission_id", "m"}, {"stages", nlohmann::json::array()}}); },
                        "stages: expected at least one stage");
  expect_contract_error(
      [] { JobRequest::from_json({{"mission_id", "m"}, {"stages", {"map"}}, {"options", {{"map", 1}}}}); },
      "options.map: expected object");
}

TEST(Contracts, OptionAssignmentsParseJsonValuesOrStrings) {
  nlohmann::json options = nlohmann::json::object();
  apply_option_assignment(options, "map.voxel_m=0.05");
  apply_option_assignment(options, "refine.dvl=false");
  apply_option_assignment(options, "map.sensors=[\"lidar_h\"]");
  apply_option_assignment(options, "ba.mode=proposed");
  EXPECT_DOUBLE_EQ(options["map"]["voxel_m"].get<double>(), 0.05);
  EXPECT_FALSE(options["refine"]["dvl"].get<bool>());
  EXPECT_EQ(options["map"]["sensors"][0], "lidar_h");
  EXPECT_EQ(options["ba"]["mode"], "proposed");
  expect_contract_error([&] { apply_option_assignment(options, "voxel=1"); }, "expected stage.option=value");
  expect_contract_error([&] { apply_option_assignment(options, "warp.speed=9"); }, "unknown stage 'warp'");
  expect_contract_error([&] { apply_option_assignment(options, "map.x"); }, "expected stage.option=value");
}

TEST(Contracts, StageListParsing) {
  EXPECT_EQ(parse_stage_list("ingest,refine,map"), (std::vector<std::string>{"ingest", "refine", "map"}));
  expect_contract_error([] { parse_stage_list("ingest,ingest"); }, "repeated");
  expect_contract_error([] { parse_stage_list(""); }, "at least one");
}

TEST(Contracts, ResourcesRoundTripAndValidateHashes) {
  Upload upload{"u_1", "m.tar", 100, 40, ""};
  EXPECT_EQ(Upload::from_json(upload.to_json()).to_json(), upload.to_json());
  Mission mission{"m_1", "bridge", kSha, "", "", 5};
  EXPECT_EQ(Mission::from_json(mission.to_json()).to_json(), mission.to_json());
  Artifact artifact{"a_1", "j_1", "ingest", "report.json", kSha, 12, 7};
  EXPECT_EQ(Artifact::from_json(artifact.to_json()).to_json(), artifact.to_json());
  expect_contract_error([] { MissionRequest::from_json({{"name", "x"}, {"bundle_blob", "abc"}}); },
                        "bundle_blob: expected 64 lowercase hex");
  expect_contract_error([] { MissionRequest::from_json({{"name", "x"}, {"bundle_blob", kSha}, {"cad_blob", kSha}}); },
                        "cad_name: required");
  expect_contract_error([] { UploadRequest::from_json({{"size", -1}}); }, "size: expected a size >= 0");
  expect_contract_error([] { UploadRequest::from_json(nlohmann::json::array()); }, "expected object, got array");
}

TEST(Contracts, WorkerProtocolRoundTrip) {
  Lease lease;
  lease.lease_id = "l_1";
  lease.expires_at_ms = 99;
  lease.job.id = "j_1";
  lease.job.mission_id = "m_1";
  lease.job.stages = {"ingest"};
  lease.mission = {"m_1", "bridge", kSha, kSha, "hull.ply", 1};
  lease.completed.push_back({"ingest", {{"imu_rate_hz", 200}}, {{"a", "j_1", "ingest", "r.json", kSha, 3, 0}}, 1.0});
  EXPECT_EQ(Lease::from_json(nlohmann::json::parse(lease.to_json().dump())).to_json(), lease.to_json());

  Heartbeat beat{"l_1", "ingest", 0.5, {"line one", "line two"}};
  EXPECT_EQ(Heartbeat::from_json(beat.to_json()).to_json(), beat.to_json());
  expect_contract_error([] { Heartbeat::from_json({{"lease_id", "l"}, {"progress", 1.5}}); }, "progress");
  expect_contract_error(
      [] { ArtifactRegistration::from_json({{"lease_id", "l"}, {"stage", "s"}, {"name", "../x"}, {"blob", kSha}}); },
      "name: expected a plain file name");
  LogPage page{{{0, 1, "a"}, {1, 2, "b"}}, 2};
  EXPECT_EQ(LogPage::from_json(page.to_json()).to_json(), page.to_json());
}

TEST(Contracts, ApiErrorRoundTrip) {
  ApiError error{"not_found", "job j_9 not found"};
  const ApiError back = ApiError::from_json(error.to_json());
  EXPECT_EQ(back.code, "not_found");
  EXPECT_EQ(back.message, "job j_9 not found");
  expect_contract_error([] { ApiError::from_json({{"error", {{"code", "x"}}}}); }, "error.message: missing");
}

}  // namespace
}  // namespace keel::proto
