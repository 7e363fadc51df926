// POST /v1/comparisons through the pure handler: a compare job over two finished jobs, the
// lease that hands the worker both jobs and their artifacts, and every refusal with its reason.
#include "tests/server/handler_fixture.h"

namespace keel::server::testing {
namespace {

class ComparisonsRoutesTest : public HandlerTest {
 protected:
  // Runs a job to success, registering artifacts with these names (one stage, `stage`).
  void finish(const std::string& id, const std::string& stage,
              const std::vector<std::string>& artifacts) {
    const nlohmann::json leased = lease();
    ASSERT_EQ(leased["job"]["id"], id);
    const std::string lease_id = leased["lease_id"];
    for (const std::string& name : artifacts) {
      const std::string blob = upload(random_bytes(64, name.size()));
      Response r = post("/v1/worker/jobs/" + id + "/artifacts",
                        {{"lease_id", lease_id}, {"stage", stage}, {"name", name}, {"blob", blob}});
      ASSERT_LT(r.status, 300) << r.body;
    }
    ASSERT_EQ(post("/v1/worker/jobs/" + id + "/stages/" + stage + "/complete",
                   {{"lease_id", lease_id}, {"report", nlohmann::json::object()}})
                  .status,
              204);
    ASSERT_EQ(post("/v1/worker/jobs/" + id + "/complete", {{"lease_id", lease_id}}).status, 200);
  }

  std::string map_job(const std::string& mission) {
    const std::string id = create_job(mission, {"map"})["id"];
    finish(id, "map", {"map_combined.drc", "report.json"});
    return id;
  }

  Response compare(const std::string& a, const std::string& b,
                   const nlohmann::json& options = nlohmann::json::object()) {
    return post("/v1/comparisons", {{"job_a", a}, {"job_b", b}, {"options", options}});
  }
};

TEST_F(ComparisonsRoutesTest, MakesACompareJobWhoseLeaseCarriesBothJobs) {
  const std::string mission = create_mission("m1")["id"];
  const std::string a = map_job(mission), b = map_job(create_mission("m2")["id"]);
  Response made = compare(a, b, {{"core_spacing_m", 0.05}});
  ASSERT_EQ(made.status, 201) << made.body;
  const nlohmann::json job = json_of(made);
  EXPECT_EQ(job["stages"], nlohmann::json({"compare"}));
  EXPECT_EQ(job["options"]["compare"]["job_a"], a);
  EXPECT_EQ(job["options"]["compare"]["job_b"], b);
  EXPECT_EQ(job["options"]["compare"]["core_spacing_m"], 0.05);

  const nlohmann::json leased = lease();
  EXPECT_EQ(leased["job"]["id"], job["id"]);
  ASSERT_EQ(leased["inputs"].size(), 2u);
  EXPECT_EQ(leased["inputs"][0]["job"]["id"], a);
  EXPECT_EQ(leased["inputs"][1]["job"]["id"], b);
  EXPECT_EQ(leased["inputs"][0]["artifacts"].size(), 2u);
  EXPECT_EQ(leased["inputs"][0]["artifacts"][0]["name"], "map_combined.drc");
  // The lease parses on the worker's side.
  const proto::Lease parsed = proto::Lease::from_json(leased);
  EXPECT_EQ(parsed.inputs.size(), 2u);
}

TEST_F(ComparisonsRoutesTest, RefusesWithTheReason) {
  const std::string mission = create_mission("m1")["id"];
  const std::string a = map_job(mission);
  const std::string hull = create_job(create_mission("m2")["id"], {"inspect"})["id"];
  finish(hull, "inspect", {"mesh_remeshed.drc", "shapes.json", "report.json"});

  Response r = compare(a, hull);
  EXPECT_EQ(r.status, 409);
  EXPECT_EQ(error_code_of(r), "not_comparable");
  EXPECT_NE(r.body.find("a map compares with a map, a hull with a hull"), std::string::npos)
      << r.body;

  const std::string queued = create_job(mission, {"map"})["id"];
  r = compare(a, queued);
  EXPECT_EQ(r.status, 409);
  EXPECT_NE(r.body.find("job " + queued + " is queued"), std::string::npos) << r.body;

  r = compare(a, "j_nope");
  EXPECT_EQ(r.status, 404) << r.body;
  EXPECT_EQ(post("/v1/comparisons", {{"job_a", a}}).status, 400);
  EXPECT_EQ(compare(a, a, {{"job_a", "x"}}).status, 400);
  EXPECT_EQ(compare(a, a, nlohmann::json::array()).status, 400);
  // A job with itself is allowed: zero change.
  EXPECT_EQ(compare(a, a).status, 201);
}

}  // namespace
}  // namespace keel::server::testing
