#include "tests/fuzz/contract_seeds.h"

#include <fstream>
#include <stdexcept>
#include <string>

#include "tests/fuzz/json_contracts.h"

namespace keel::fuzz {
namespace {

const std::string kSha = "9f86d081884c7d659a2feaa0c55ad015a3bf4f1b2b0b822cd15d6c15b0f00a08";

const std::string kMission = R"({"id":"m_7","name":"usv-bridge-2026-11","bundle_blob":")" + kSha +
                             R"(","cad_blob":"","cad_name":"","created_at_ms":1764288000000,
  "project":"harbour"})";

const std::string kJob = R"({"id":"j_42","mission_id":"m_7","state":"running",
  "stages":["ingest","refine","map","ba","inspect"],"options":{"map":{"voxel_m":0.05}},
  "stage":"map","progress":0.5,"completed_stages":["ingest","refine"],
  "stage_seconds":{"ingest":1.5,"refine":12.25},"error":"","attempts":2,
  "created_at_ms":1764288000000,"started_at_ms":1764288001000,"finished_at_ms":0,
  "project":"harbour","batch_id":"b_3","worker":"host:123:1764288000","mission_name":"usv-bridge-2026-11"})";

const std::string kArtifact =
    R"({"id":"a_9","job_id":"j_42","stage":"map","name":"map_combined.drc",
  "sha256":")" +
    kSha + R"(","size":1048576,"created_at_ms":1764288100000,"project":"harbour"})";

const std::string kStageOutput = R"({"stage":"ingest","report":{"imu_samples":12000,"warnings":[]},
  "artifacts":[)" + kArtifact + R"(],"seconds":1.5})";

const std::string kManifest = R"({"keel_mission":1,"name":"hauv-hull.seed_1","platform":"hauv",
  "body_frame":"base_link","world_frame":"world","bag":"mission.mcap",
  "sensors":[
    {"name":"imu","type":"imu","topic":"/imu/data","frame_id":"imu_link","rate_hz":200,
     "T_body_sensor":{"translation":[0.1,0,-0.05],"rotation_xyzw":[0,0,0.7071068,0.7071068]},
     "noise":{"gyro_noise_density":5.7e-4,"accel_noise_density":9.4e-4,
              "gyro_random_walk":3.7e-6,"accel_random_walk":2.4e-6}},
    {"name":"dvl","type":"dvl","topic":"/dvl/twist","rate_hz":5,
     "noise":{"velocity_sigma_rel":1e-3,"bias_random_walk_rel":1e-4}},
    {"name":"dvl_ranges","type":"dvl_ranges","file":"dvl_ranges.csv","rate_hz":5,
     "range_m":[0.3,50],"beams":[[0.5,0,0.866],[-0.5,0,0.866],[0,0.5,0.866],[0,-0.5,0.866]]},
    {"name":"lidar","type":"lidar","topic":"/points","rate_hz":10,"range_m":[0.5,100],
     "point_time":{"field":"t","unit":"ns","reference":"scan_start"},"mounted_on":"servo"},
    {"name":"servo","type":"servo","file":"servo.csv","rate_hz":20,"axis":[0,1,0]},
    {"name":"cam0","type":"camera","topic":"/cam0/image/compressed","rate_hz":4,
     "camera":{"model":"kannala_brandt","width":1280,"height":1024,"fx":610,"fy":611,
               "cx":640.5,"cy":512.25,"distortion":[0.01,-0.002,0.0003,-0.00004]}},
    {"name":"depth","type":"depth","file":"depth.csv","rate_hz":10}],
  "trajectories":{"odometry":{"topic":"/odom"}},
  "loop_closures":"loops.csv","ground_truth":"truth.yaml","cad_mesh":"hull.ply"})";

const std::string kFolderManifest = R"({"keel_mission":1,"name":"usv-bridge","platform":"usv",
  "sensors":[
    {"name":"imu","type":"imu","file":"imu.csv","rate_hz":200},
    {"name":"lidar_h","type":"lidar","scans":"lidar_h","rate_hz":10,
     "point_time":{"field":"time","unit":"s","reference":"absolute"},
     "noise":{"range_sigma":0.02}},
    {"name":"cam0","type":"camera","images":"cam0","rate_hz":10,
     "camera":{"model":"pinhole","width":752,"height":480,"fx":458.654,"fy":457.296,
               "cx":367.215,"cy":248.375,"distortion":[-0.28340811,0.07395907,0.00019359,1.76187114e-05]}}],
  "trajectories":{"odometry":"odometry.tum","map":"map_poses.tum","ground_truth":"truth.tum"}})";

// Selector (json_contracts.h's order) and document.
const std::pair<int, std::string> kSeeds[] = {
    {0, R"({"error":{"code":"not_found","message":"job j_9 not found"}})"},
    {1, R"({"id":"t_1","label":"field laptop","role":"submitter","project":"harbour",
        "created_at_ms":1764288000000,"expires_at_ms":1764374400000,"revoked_at_ms":0})"},
    {2, R"({"label":"ci","role":"viewer","project":"harbour","expires_in_s":86400})"},
    {2, R"({"label":"workers","role":"worker","project":"*"})"},
    {3,
     R"({"name":"harbour","created_at_ms":1764288000000,"quota_bytes":10737418240,"used_bytes":52428800})"},
    {4, R"({"mission_id":"m_7","stages":["ingest","refine","map"],"options":{"map":{"voxel_m":0.1}},
        "project":"harbour"})"},
    {5, kJob},
    {6, R"({"job_a":"j_1","job_b":"j_2","options":{"compare":{"threshold_m":0.02}}})"},
    {7, R"({"mission_ids":["m_1","m_2"],"stages":["map"],"options":{},"compare":true})"},
    {7, R"({"name_prefix":"usv-","stages":["ingest","map"],"project":"harbour"})"},
    {8, R"({"id":"b_3","project":"harbour","created_at_ms":1764288000000,"jobs":12,"compared":4,
        "jobs_by_state":{"queued":2,"running":1,"succeeded":8,"failed":1,"canceled":0},
        "mean_job_seconds":95.5,"finished_jobs_timed":9})"},
    {9,
     R"({"id":"u_5","name":"mission.tar","size":104857600,"offset":8388608,"blob":"","project":"harbour"})"},
    {10, R"({"name":"mission.tar","size":104857600,"project":"harbour"})"},
    {11, kMission},
    {12, R"({"name":"usv-bridge-2026-11","bundle_blob":")" + kSha + R"(","cad_blob":")" + kSha +
             R"(","cad_name":"hull.stl","project":"harbour"})"},
    {13, kArtifact},
    {14, R"({"worker":"host:123:1764288000","lease_seconds":60,"wait_seconds":20})"},
    {15, R"({"lease_id":"l_1","expires_at_ms":1764288060000,"job":)" + kJob + R"(,"mission":)" +
             kMission + R"(,"completed":[)" + kStageOutput + R"(],"inputs":[{"job":)" + kJob +
             R"(,"artifacts":[)" + kArtifact + R"(]}]})"},
    {16, R"({"lease_id":"l_1","stage":"map","progress":0.25,"log":["map: 120 of 480 scans"]})"},
    {17, R"({"canceled":false,"expires_at_ms":1764288060000})"},
    {18, R"({"lease_id":"l_1","stage":"map","name":"map_combined.drc","blob":")" + kSha + R"("})"},
    {19, R"({"lease_id":"l_1","report":{"scans":480,"points":1200000},"seconds":61.5})"},
    {20, R"({"lease_id":"l_1","error":"ingest: imu.csv:12: t decreases"})"},
    {21, R"({"lines":[{"seq":1,"t_ms":1764288000000,"text":"[ingest] 0%"},
        {"seq":2,"t_ms":1764288000500,"text":"[ingest] 100%"}],"next":3})"},
    {22, kManifest},
    {22, kFolderManifest},
    {23, kStageOutput},
};

}  // namespace

int write_contract_seeds(const std::filesystem::path& dir) {
  int n = 0;
  for (const auto& [selector, text] : kSeeds) {
    std::string refusal;
    if (!read_contract(selector, nlohmann::json::parse(text), &refusal))
      throw std::runtime_error(std::string("seed for ") + contract_name(selector) +
                               " is refused: " + refusal);
    std::ofstream(dir / (std::string(contract_name(selector)) + "-" + std::to_string(n++)),
                  std::ios::binary)
        << static_cast<char>(selector) << text;
  }
  return n;
}

}  // namespace keel::fuzz
