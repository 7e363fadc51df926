// Comparisons through the server (issue 16): two keel-sim surveys of one bridge, mapped by a
// real worker, compared with `keel compare`; a reprocess with `--compare` compares each new
// job with the job it reprocesses; pairs that cannot be compared are refused with the reason.
#include <gtest/gtest.h>

#include <fstream>
#include <regex>

#include "core/sha256.h"
#include "tests/e2e/cluster.h"

namespace keel::e2e {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using proto::JobState;

constexpr const char* kStages = "ingest,refine,map";

void simulate_survey(const fs::path& out, int survey) {
  const RunResult r = run_command(
      {Programs().sim.string(), "--scenario", "usv-bridge", "--seed", "2", "--survey",
       std::to_string(survey), "--duration", "20", "--sensors", "imu,dvl,lidar_h,depth", "--out",
       out.string()},
      std::chrono::seconds(600));
  ASSERT_EQ(r.exit_code, 0) << r.output;
}

std::string job_id_in(const std::string& text) {
  std::smatch match;
  const std::regex id("j_[0-9a-f]+");
  if (!std::regex_search(text, match, id)) ADD_FAILURE() << "no job id in: " << text;
  return match.str();
}

// report.json of a finished job, fetched with the CLI (SHA-256 checked by it).
json fetched_report(const Cluster& cluster, const std::string& job, const fs::path& out) {
  const RunResult fetched = cluster.keel({"fetch", job, "-o", out.string(), "-q"});
  EXPECT_EQ(fetched.exit_code, 0) << fetched.output;
  std::ifstream in(out / "report.json");
  return json::parse(in);
}

TEST(CompareThroughTheServer, SurveysComparedAndAReprocessComparedWithTheJobItReprocesses) {
  TempDir root;
  simulate_survey(root.path() / "survey-1", 1);
  simulate_survey(root.path() / "survey-2", 2);
  Cluster cluster(root.path(), /*workers=*/1);
  auto submit = [&](const std::string& mission, const std::string& stages) {
    const RunResult r = cluster.keel(
        {"submit", (root.path() / mission).string(), "--stages", stages, "--wait", "-q"}, 900);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return job_id_in(r.output);
  };
  const std::string a = submit("survey-1", kStages);
  const std::string b = submit("survey-2", kStages);
  const std::string ingest_only = submit("survey-2", "ingest");

  // keel compare A B: a compare job whose report and artifacts say what changed.
  const RunResult compared = cluster.keel({"compare", a, b, "--wait"}, 900);
  ASSERT_EQ(compared.exit_code, 0) << compared.output;
  const std::string c = job_id_in(compared.output);
  auto api = cluster.api();
  EXPECT_EQ(api.get_job(c).stages, std::vector<std::string>{"compare"});
  const json report = fetched_report(cluster, c, root.path() / "c")["stages"]["compare"];
  EXPECT_EQ(report["job_a"], a);
  EXPECT_EQ(report["job_b"], b);
  EXPECT_EQ(report["kind"], "maps");
  EXPECT_FALSE(report["runs"]["same_mission"].get<bool>());
  const json& combined = report["maps"]["maps"]["combined"];
  EXPECT_GT(combined["core_points"].get<int64_t>(), 0);
  std::set<std::string> names;
  for (const proto::Artifact& artifact : api.list_artifacts(c)) names.insert(artifact.name);
  for (const char* name : {"change_combined.drc", "change_combined.json", "changes.json"})
    EXPECT_TRUE(names.count(name)) << name;
  const json sidecar = json::parse(std::ifstream(root.path() / "c" / "change_combined.json"));
  EXPECT_EQ(sidecar["points"], combined["points_b"]);

  // Refused with the reason, and no job made: a map job against an ingest-only job, an
  // unfinished (here: unknown) job.
  const size_t jobs_before = api.list_jobs().size();
  const RunResult refused = cluster.keel({"compare", a, ingest_only});
  EXPECT_EQ(refused.exit_code, 2) << refused.output;
  EXPECT_NE(refused.output.find("a map compares with a map"), std::string::npos) << refused.output;
  const RunResult unknown = cluster.keel({"compare", a, "j_0000000000000000"});
  EXPECT_EQ(unknown.exit_code, 2) << unknown.output;
  EXPECT_EQ(api.list_jobs().size(), jobs_before);

  // keel reprocess --compare: the new job on survey-1 runs its stages, then compares with A,
  // the mission's latest succeeded job (the comparison job C is not a candidate).
  const std::string mission_a = api.get_job(a).mission_id;
  const RunResult again = cluster.keel(
      {"reprocess", "--mission", mission_a, "--stages", kStages, "--compare", "--set",
       "map.metrics_radius_m=0.3"});
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_NE(again.output.find("1 of them compare with the job they reprocess"), std::string::npos)
      << again.output;
  const std::string r = job_id_in(again.output);
  const proto::Job done = wait_job(api, r, [](const proto::Job& j) { return proto::is_terminal(j.state); }, 900);
  ASSERT_EQ(done.state, JobState::kSucceeded) << done.error;
  EXPECT_EQ(done.stages, (std::vector<std::string>{"ingest", "refine", "map", "compare"}));
  const json full = fetched_report(cluster, r, root.path() / "r");
  const json& rc = full["stages"]["compare"];
  EXPECT_EQ(rc["job_a"], a);
  EXPECT_EQ(rc["job_b"], r);
  EXPECT_TRUE(rc["runs"]["same_mission"].get<bool>());
  bool radius_listed = false;
  for (const json& d : rc["runs"]["options_differ"])
    radius_listed |= d["option"] == "map.metrics_radius_m" && d["b"] == 0.3;
  EXPECT_TRUE(radius_listed) << rc["runs"]["options_differ"].dump();
  // The same survey mapped twice: its maps hardly differ (the registration absorbs nothing).
  EXPECT_LT(rc["maps"]["maps"]["combined"]["significant_fraction"].get<double>(), 0.01);
  // Its own products are there as well as the comparison's.
  std::set<std::string> own;
  for (const proto::Artifact& artifact : api.list_artifacts(r)) own.insert(artifact.name);
  for (const char* name : {"map_combined.drc", "trajectory_refined.tum", "change_combined.drc"})
    EXPECT_TRUE(own.count(name)) << name;
}

}  // namespace
}  // namespace keel::e2e
