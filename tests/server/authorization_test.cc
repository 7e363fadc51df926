// The authorization matrix of docs/api.md ("Who may do what"), read from the document itself:
// every route x every role x an object of the token's own project and of another project,
// each answer's exact status. Then expired and revoked tokens, the admin API's scoping, and
// blobs that only their project may fetch or name.
#include <gtest/gtest.h>

#include <fstream>
#include <functional>
#include <map>
#include <regex>
#include <sstream>

#include "tests/server/handler_fixture.h"

namespace keel::server::testing {
namespace {

const char* const kRoles[] = {"admin", "submitter", "viewer", "worker"};

struct MatrixRow {
  std::string method;
  std::string path;                          // as written, with {id} etc.
  std::map<std::string, std::string> cells;  // role -> "yes", "-" or "*"
};

// The rows of the table under "## Who may do what" in docs/api.md.
std::vector<MatrixRow> read_matrix() {
  std::ifstream in(std::string(KEEL_SOURCE_DIR) + "/docs/api.md");
  EXPECT_TRUE(in) << "docs/api.md not found";
  std::string line;
  bool in_section = false;
  std::vector<MatrixRow> rows;
  const std::regex row_pattern(
      R"(^\| `(GET|HEAD|PUT|POST|DELETE) ([^`]+)` \| (\S+) \| (\S+) \| (\S+) \| (\S+) \|$)");
  while (std::getline(in, line)) {
    if (line.rfind("## ", 0) == 0) in_section = line == "## Who may do what";
    std::smatch match;
    if (!in_section || !std::regex_match(line, match, row_pattern)) continue;
    MatrixRow row;
    row.method = match[1];
    row.path = match[2];
    for (int i = 0; i < 4; ++i) row.cells[kRoles[i]] = match[3 + i];
    rows.push_back(row);
  }
  return rows;
}

// One project's objects, made through the API by an admin token of every project.
struct Objects {
  std::string project;
  std::string open_upload;  // 10 bytes announced, none sent
  std::string full_upload;  // 10 bytes sent, not completed
  std::string full_bytes;
  std::string bundle_blob;
  std::string extra_blob;  // uploaded in this project, for artifact registration
  std::string mission;
  std::string running_job;
  std::string lease_id;
  std::string queued_job;
  std::string canceled_job;
  std::string artifact;
  std::string batch;
  std::string token_id;  // a viewer token of this project
};

struct Request2 {
  std::string method;
  std::string target;
  std::string body;
  std::map<std::string, std::string> headers;
};

Request2 json_call(const std::string& method, const std::string& target,
                   const nlohmann::json& body) {
  return {method, target, body.dump(), {}};
}

enum class Kind {
  kObject,   // own: `success`; another project's object: 404
  kListing,  // 200 either way; own ids listed, the other project's not
  kGlobal,   // the same answer either way (server-wide)
};

class AuthorizationTest : public HandlerTest {
 protected:
  void SetUp() override {
    HandlerTest::SetUp();
    build_world();
  }

  // A fresh store for the next cell (the previous call may have changed things).
  void rebuild() {
    handler_.reset();
    store_.reset();
    world_dir_ = std::make_unique<TempDir>();
    store_ = storage::open_sqlite_store(world_dir_->path());
    store_->add_token(token_, storage::admin_token("tests"));
    handler_ = std::make_unique<HttpHandler>(*store_, HandlerOptions{});
    build_world();
  }

  std::string id_of(const Response& response, int status) {
    EXPECT_EQ(response.status, status) << response.body;
    return json_of(response)["id"];
  }

  Objects make_objects(const std::string& project) {
    Objects o;
    o.project = project;
    auto new_upload = [&](const std::string& name) {
      return id_of(post("/v1/uploads", {{"name", name}, {"size", 10}, {"project", project}}), 201);
    };
    auto uploaded = [&](const std::string& bytes) {
      const std::string id = id_of(
          post("/v1/uploads", {{"name", "b"}, {"size", bytes.size()}, {"project", project}}), 201);
      EXPECT_EQ(call("PUT", "/v1/uploads/" + id, bytes,
                     {{"Content-Range", "bytes 0-" + std::to_string(bytes.size() - 1) + "/" +
                                            std::to_string(bytes.size())}})
                    .status,
                200);
      Response done =
          post("/v1/uploads/" + id + "/complete", {{"sha256", keel::sha256_bytes(bytes)}});
      EXPECT_EQ(done.status, 200) << done.body;
      return json_of(done)["blob"].get<std::string>();
    };
    o.open_upload = new_upload("open.bin");
    o.full_upload = new_upload("full.bin");
    o.full_bytes = "0123456789";
    EXPECT_EQ(call("PUT", "/v1/uploads/" + o.full_upload, o.full_bytes,
                   {{"Content-Range", "bytes 0-9/10"}})
                  .status,
              200);
    o.bundle_blob = uploaded(valid_bundle(project + "-mission"));
    o.extra_blob = uploaded("artifact of " + project);
    o.mission = id_of(post("/v1/missions", {{"name", project + "-mission"},
                                            {"bundle_blob", o.bundle_blob},
                                            {"project", project}}),
                      201);
    auto new_job = [&] {
      return id_of(post("/v1/jobs", {{"mission_id", o.mission}, {"stages", {"ingest"}}}), 201);
    };
    // Leased at once, so the lease takes this job (the only one queued).
    o.running_job = new_job();
    storage::TokenSpec worker;
    worker.role = proto::Role::kWorker;
    worker.project = project;
    store_->add_token("setup-worker-" + project, worker);
    Response lease = send("setup-worker-" + project,
                          json_call("POST", "/v1/worker/lease",
                                    {{"worker", "setup:" + project}, {"lease_seconds", 600}}));
    EXPECT_EQ(lease.status, 200) << lease.body;
    EXPECT_EQ(json_of(lease)["job"]["id"], o.running_job);
    o.lease_id = json_of(lease)["lease_id"];
    Response artifact = post(
        "/v1/worker/jobs/" + o.running_job + "/artifacts",
        {{"lease_id", o.lease_id}, {"stage", "ingest"}, {"name", "a.txt"}, {"blob", o.extra_blob}});
    o.artifact = id_of(artifact, 201);
    o.canceled_job = new_job();
    EXPECT_EQ(call("POST", "/v1/jobs/" + o.canceled_job + "/cancel").status, 200);
    Response batch =
        post("/v1/reprocess",
             {{"mission_ids", {o.mission}}, {"stages", {"ingest"}}, {"project", project}});
    EXPECT_EQ(batch.status, 201) << batch.body;
    o.batch = json_of(batch)["batch"]["id"];
    o.queued_job = new_job();
    Response token = post("/v1/tokens", {{"role", "viewer"}, {"project", project}});
    EXPECT_EQ(token.status, 201) << token.body;
    o.token_id = json_of(token)["info"]["id"];
    return o;
  }

  void build_world() {
    alpha_ = make_objects("alpha");
    beta_ = make_objects("beta");
    tokens_.clear();
    for (const char* role : kRoles) {
      storage::TokenSpec spec;
      spec.role = proto::role_from_string(role);
      spec.project = "alpha";
      const std::string token = std::string("alpha-") + role + "-token";
      store_->add_token(token, spec);
      tokens_[role] = token;
    }
  }

  Response send(const std::string& token, const Request2& r) {
    Request request;
    request.method = r.method;
    request.target = r.target;
    request.body = r.body;
    request.headers.set("Authorization", "Bearer " + token);
    for (const auto& [name, value] : r.headers) request.headers.set(name, value);
    return handler_->handle(request);
  }

  struct Case {
    Kind kind = Kind::kObject;
    int own = 200;    // an allowed role on its own project's object
    int other = 404;  // an allowed role on the other project's object
    Request2 request;
    std::string marker;        // kListing: what the own project's listing holds
    std::string other_marker;  // kListing: what it must not hold
  };

  // The case of `route` ("METHOD /path" as in the document) on `o`'s objects; `other` says
  // that `o` is the other project's (some routes prepare the world for that).
  bool make_case(const std::string& route, const Objects& o, bool other, Case& c);

  std::unique_ptr<TempDir> world_dir_;
  Objects alpha_, beta_;
  std::map<std::string, std::string> tokens_;
};

bool AuthorizationTest::make_case(const std::string& route, const Objects& o, bool other, Case& c) {
  const Objects& own = alpha_;
  const Objects& foreign = beta_;
  auto get = [&](const std::string& target) { c.request = {"GET", target, "", {}}; };
  auto listing = [&](const std::string& target, const std::string& own_marker,
                     const std::string& other_marker) {
    c.kind = Kind::kListing;
    c.other = 200;
    c.marker = own_marker;
    c.other_marker = other_marker;
    get(target);
  };
  if (route == "POST /v1/uploads") {
    c.own = 201;
    c.request =
        json_call("POST", "/v1/uploads", {{"name", "x"}, {"size", 3}, {"project", o.project}});
  } else if (route == "HEAD /v1/uploads/{id}") {
    c.request = {"HEAD", "/v1/uploads/" + o.open_upload, "", {}};
  } else if (route == "GET /v1/uploads/{id}") {
    get("/v1/uploads/" + o.open_upload);
  } else if (route == "PUT /v1/uploads/{id}") {
    c.request = {
        "PUT", "/v1/uploads/" + o.open_upload, "abcdefghij", {{"Content-Range", "bytes 0-9/10"}}};
  } else if (route == "DELETE /v1/uploads/{id}") {
    c.own = 204;
    c.request = {"DELETE", "/v1/uploads/" + o.open_upload, "", {}};
  } else if (route == "POST /v1/uploads/{id}/complete") {
    c.request = json_call("POST", "/v1/uploads/" + o.full_upload + "/complete",
                          {{"sha256", keel::sha256_bytes(o.full_bytes)}});
  } else if (route == "GET /v1/blobs/{sha256}") {
    get("/v1/blobs/" + o.extra_blob);
  } else if (route == "POST /v1/missions") {
    c.own = 201;
    c.request =
        json_call("POST", "/v1/missions",
                  {{"name", "new"}, {"bundle_blob", o.bundle_blob}, {"project", o.project}});
  } else if (route == "GET /v1/missions") {
    listing("/v1/missions", own.mission, foreign.mission);
  } else if (route == "GET /v1/missions/{id}") {
    get("/v1/missions/" + o.mission);
  } else if (route == "POST /v1/jobs") {
    c.own = 201;
    c.request = json_call("POST", "/v1/jobs", {{"mission_id", o.mission}, {"stages", {"ingest"}}});
  } else if (route == "POST /v1/comparisons") {
    // Reached: refused for the job's state (409); another project's jobs: 404.
    c.own = 409;
    c.request = json_call("POST", "/v1/comparisons",
                          {{"job_a", o.canceled_job}, {"job_b", o.canceled_job}});
  } else if (route == "GET /v1/jobs") {
    listing("/v1/jobs", own.queued_job, foreign.queued_job);
  } else if (route == "GET /v1/jobs/{id}") {
    get("/v1/jobs/" + o.queued_job);
  } else if (route == "GET /v1/jobs/{id}/log") {
    get("/v1/jobs/" + o.running_job + "/log");
  } else if (route == "POST /v1/jobs/{id}/cancel") {
    c.request = {"POST", "/v1/jobs/" + o.queued_job + "/cancel", "", {}};
  } else if (route == "POST /v1/jobs/{id}/retry") {
    c.request = {"POST", "/v1/jobs/" + o.canceled_job + "/retry", "", {}};
  } else if (route == "GET /v1/jobs/{id}/artifacts") {
    get("/v1/jobs/" + o.running_job + "/artifacts");
  } else if (route == "POST /v1/reprocess") {
    c.own = 201;
    c.request =
        json_call("POST", "/v1/reprocess", {{"mission_ids", {o.mission}}, {"stages", {"ingest"}}});
  } else if (route == "GET /v1/artifacts/{id}") {
    get("/v1/artifacts/" + o.artifact);
  } else if (route == "GET /v1/artifacts/{id}/files/{path}") {
    // Reached: the artifact is no tar, so it has no members (404 either way; the message
    // tells the two apart).
    c.own = 404;
    get("/v1/artifacts/" + o.artifact + "/files/tileset.json");
  } else if (route == "GET /v1/batches/{id}") {
    get("/v1/batches/" + o.batch);
  } else if (route == "GET /v1/events") {
    get("/v1/events?job_id=" + o.queued_job);
  } else if (route == "GET /v1/queue") {
    c.kind = Kind::kGlobal;
    c.other = 200;
    get("/v1/queue");
  } else if (route == "POST /v1/worker/lease") {
    // Own: the caller's project has queued jobs. Other: only the other project has any, so
    // the caller is given nothing.
    c.other = 204;
    if (other) {
      storage::JobFilter queued;
      queued.state = proto::JobState::kQueued;
      queued.project = "alpha";
      for (const proto::Job& job : store_->list_jobs(queued)) store_->cancel_job(job.id);
    }
    c.request = json_call("POST", "/v1/worker/lease", {{"worker", "w:1"}, {"lease_seconds", 30}});
  } else if (route == "POST /v1/worker/jobs/{id}/release") {
    c.request = json_call("POST", "/v1/worker/jobs/" + o.running_job + "/release",
                          {{"lease_id", o.lease_id}});
  } else if (route == "POST /v1/worker/jobs/{id}/heartbeat") {
    c.request = json_call("POST", "/v1/worker/jobs/" + o.running_job + "/heartbeat",
                          {{"lease_id", o.lease_id}, {"stage", "ingest"}, {"progress", 0.5}});
  } else if (route == "POST /v1/worker/jobs/{id}/artifacts") {
    c.own = 201;
    c.request = json_call(
        "POST", "/v1/worker/jobs/" + o.running_job + "/artifacts",
        {{"lease_id", o.lease_id}, {"stage", "ingest"}, {"name", "b.txt"}, {"blob", o.extra_blob}});
  } else if (route == "POST /v1/worker/jobs/{id}/stages/{stage}/complete") {
    c.own = 204;
    c.request = json_call(
        "POST", "/v1/worker/jobs/" + o.running_job + "/stages/ingest/complete",
        {{"lease_id", o.lease_id}, {"report", nlohmann::json::object()}, {"seconds", 1.0}});
  } else if (route == "POST /v1/worker/jobs/{id}/complete") {
    c.request = json_call("POST", "/v1/worker/jobs/" + o.running_job + "/complete",
                          {{"lease_id", o.lease_id}});
  } else if (route == "POST /v1/worker/jobs/{id}/fail") {
    c.request = json_call("POST", "/v1/worker/jobs/" + o.running_job + "/fail",
                          {{"lease_id", o.lease_id}, {"error", "broken"}});
  } else if (route == "POST /v1/tokens") {
    c.own = 201;
    c.request = json_call("POST", "/v1/tokens", {{"role", "submitter"}, {"project", o.project}});
  } else if (route == "GET /v1/tokens") {
    listing("/v1/tokens", own.token_id, foreign.token_id);
  } else if (route == "POST /v1/tokens/{id}/revoke") {
    c.request = {"POST", "/v1/tokens/" + o.token_id + "/revoke", "", {}};
  } else if (route == "GET /v1/projects") {
    listing("/v1/projects", "\"name\":\"alpha\"", "\"name\":\"beta\"");
  } else if (route == "GET /v1/projects/{name}") {
    get("/v1/projects/" + o.project);
  } else if (route == "PUT /v1/projects/{name}") {
    c.request = json_call("PUT", "/v1/projects/" + o.project, {{"quota_bytes", 1 << 20}});
  } else {
    return false;
  }
  return true;
}

TEST_F(AuthorizationTest, EveryRouteOfTheDocumentTimesEveryRoleAndProjectAnswersAsItSays) {
  const std::vector<MatrixRow> rows = read_matrix();
  ASSERT_GE(rows.size(), 35u) << "the matrix in docs/api.md was not found or lost rows";
  int cells = 0;
  bool dirty = false;
  for (const MatrixRow& row : rows) {
    const std::string route = row.method + " " + row.path;
    for (const char* role : kRoles) {
      const std::string cell = row.cells.at(role);
      ASSERT_TRUE(cell == "yes" || cell == "-" || cell == "*")
          << route << " " << role << ": " << cell;
      for (bool other : {false, true}) {
        // A fresh world after anything that may have changed it (saves ~90% of rebuilds).
        if (dirty) rebuild();
        dirty = route == "POST /v1/worker/lease";
        Case c;
        ASSERT_TRUE(make_case(route, other ? beta_ : alpha_, other, c))
            << "no test case for the documented route " << route;
        const Response answer = send(tokens_[role], c.request);
        dirty = dirty ||
                (answer.status < 300 && c.request.method != "GET" && c.request.method != "HEAD");
        const std::string what = route + " as " + role + " of alpha on " +
                                 (other ? "beta's" : "alpha's") + " object: " + answer.body;
        ++cells;
        if (cell != "yes") {
          // "-": the role may not; "*": only a token of every project may (these are of one).
          EXPECT_EQ(answer.status, 403) << what;
          EXPECT_EQ(error_code_of(answer), "forbidden") << what;
          continue;
        }
        EXPECT_EQ(answer.status, other ? c.other : c.own) << what;
        if (c.kind == Kind::kListing) {
          EXPECT_NE(answer.body.find(c.marker), std::string::npos) << what;
          EXPECT_EQ(answer.body.find(c.other_marker), std::string::npos) << what;
        }
        if (other && c.other == 404) {
          EXPECT_EQ(error_code_of(answer), "not_found") << what;
        }
      }
    }
  }
  EXPECT_EQ(cells, static_cast<int>(rows.size()) * 8);
}

TEST_F(AuthorizationTest, StarCellsAreAllowedToATokenOfEveryProject) {
  for (const MatrixRow& row : read_matrix()) {
    if (row.cells.at("admin") != "*") continue;
    const std::string route = row.method + " " + row.path;
    for (bool other : {false, true}) {
      Case c;
      ASSERT_TRUE(make_case(route, other ? beta_ : alpha_, other, c));
      EXPECT_EQ(send(token_, c.request).status, c.own) << route;
    }
  }
  const Response project = call("GET", "/v1/projects/beta");
  ASSERT_EQ(project.status, 200) << project.body;
  EXPECT_EQ(json_of(project)["quota_bytes"], 1 << 20);
}

TEST_F(AuthorizationTest, OpenRoutesNeedNoToken) {
  EXPECT_EQ(call("GET", "/healthz", "", {}, false).status, 200);
  EXPECT_EQ(call("GET", "/metrics", "", {}, false).status, 200);
  EXPECT_EQ(call("GET", "/v1/queue", "", {}, false).status, 401);
}

TEST_F(AuthorizationTest, ExpiredAndRevokedTokensAreRefused) {
  const int64_t now = storage::system_clock_ms();
  storage::TokenSpec expired;
  expired.role = proto::Role::kAdmin;
  expired.project = "alpha";
  expired.expires_at_ms = now - 1;
  store_->add_token("expired-token", expired);
  storage::TokenSpec later = expired;
  later.expires_at_ms = now + 3'600'000;
  store_->add_token("later-token", later);

  const Request2 read{"GET", "/v1/jobs/" + alpha_.queued_job, "", {}};
  EXPECT_EQ(send("later-token", read).status, 200);
  const Response refused = send("expired-token", read);
  EXPECT_EQ(refused.status, 401);
  EXPECT_EQ(error_code_of(refused), "unauthorized");
  EXPECT_EQ(refused.headers.get("WWW-Authenticate"), "Bearer");

  // Revoked through the admin API: refused from the next request on, listed as revoked.
  const Response made = post(
      "/v1/tokens",
      {{"role", "viewer"}, {"project", "alpha"}, {"label", "shared link"}, {"expires_in_s", 600}});
  ASSERT_EQ(made.status, 201) << made.body;
  const std::string clear = json_of(made)["token"];
  const nlohmann::json info = json_of(made)["info"];
  EXPECT_EQ(info["role"], "viewer");
  EXPECT_EQ(info["label"], "shared link");
  EXPECT_NEAR(info["expires_at_ms"].get<double>(), now + 600'000.0, 60'000.0);
  EXPECT_EQ(clear.size(), 64u);
  EXPECT_EQ(send(clear, read).status, 200);
  const Response revoked = call("POST", "/v1/tokens/" + info["id"].get<std::string>() + "/revoke");
  ASSERT_EQ(revoked.status, 200) << revoked.body;
  EXPECT_GT(json_of(revoked)["revoked_at_ms"].get<int64_t>(), 0);
  EXPECT_EQ(send(clear, read).status, 401);
  EXPECT_EQ(send(clear, {"GET", "/v1/jobs", "", {}}).status, 401);
  // The store keeps only hashes: the clear token appears in no listing.
  EXPECT_EQ(call("GET", "/v1/tokens").body.find(clear), std::string::npos);
}

TEST_F(AuthorizationTest, AnAdminOfOneProjectManagesOnlyItsTokens) {
  const std::string admin = tokens_["admin"];
  const Response star =
      send(admin, json_call("POST", "/v1/tokens", {{"role", "worker"}, {"project", "*"}}));
  EXPECT_EQ(star.status, 404) << star.body;
  const Response list = send(admin, {"GET", "/v1/tokens", "", {}});
  ASSERT_EQ(list.status, 200);
  // Held here: a range-for over a member of json_of()'s temporary would read freed memory.
  const nlohmann::json listed = json_of(list);
  for (const auto& token : listed["tokens"]) EXPECT_EQ(token["project"], "alpha") << token;
  // A token it made works with the role it asked for.
  const Response made =
      send(admin, json_call("POST", "/v1/tokens", {{"role", "submitter"}, {"project", "alpha"}}));
  ASSERT_EQ(made.status, 201) << made.body;
  const std::string submitter = json_of(made)["token"];
  EXPECT_EQ(send(submitter, {"GET", "/v1/jobs/" + alpha_.queued_job, "", {}}).status, 200);
  EXPECT_EQ(send(submitter, {"GET", "/v1/tokens", "", {}}).status, 403);
  // Bad requests name the field.
  const Response bad =
      call("POST", "/v1/tokens", nlohmann::json{{"role", "viewer"}, {"project", "*"}}.dump());
  EXPECT_EQ(bad.status, 400);
  EXPECT_NE(bad.body.find("project"), std::string::npos) << bad.body;
  const Response bad_role =
      call("POST", "/v1/tokens", nlohmann::json{{"role", "root"}, {"project", "alpha"}}.dump());
  EXPECT_EQ(bad_role.status, 400);
  EXPECT_NE(bad_role.body.find("unknown role 'root'"), std::string::npos) << bad_role.body;
}

TEST_F(AuthorizationTest, ABlobIsFetchedAndNamedOnlyByAProjectThatHoldsIt) {
  const std::string submitter = tokens_["submitter"];
  // beta's bundle is unknown to alpha's tokens, whatever its hash.
  const Response fetch = send(submitter, {"GET", "/v1/blobs/" + beta_.bundle_blob, "", {}});
  EXPECT_EQ(fetch.status, 404);
  const Response fetch_unknown =
      send(submitter, {"GET", "/v1/blobs/" + std::string(64, 'a'), "", {}});
  EXPECT_EQ(fetch_unknown.status, 404);
  // The same message as for no blob at all: nothing tells the two apart.
  EXPECT_EQ(json_of(fetch)["error"]["message"], "blob " + beta_.bundle_blob + " not found");
  EXPECT_EQ(json_of(fetch_unknown)["error"]["message"],
            "blob " + std::string(64, 'a') + " not found");
  const Response mission = send(
      submitter,
      json_call("POST", "/v1/missions", {{"name", "stolen"}, {"bundle_blob", beta_.bundle_blob}}));
  EXPECT_EQ(mission.status, 404) << mission.body;
  // Once alpha uploads the same bytes, alpha holds the blob too (stored once).
  const std::string bytes = valid_bundle("beta-mission");
  const Response created = send(
      submitter, json_call("POST", "/v1/uploads", {{"name", "b.tar"}, {"size", bytes.size()}}));
  ASSERT_EQ(created.status, 201);
  const std::string id = json_of(created)["id"];
  ASSERT_EQ(send(submitter, {"PUT",
                             "/v1/uploads/" + id,
                             bytes,
                             {{"Content-Range", "bytes 0-" + std::to_string(bytes.size() - 1) +
                                                    "/" + std::to_string(bytes.size())}}})
                .status,
            200);
  const Response done = send(submitter, json_call("POST", "/v1/uploads/" + id + "/complete",
                                                  {{"sha256", beta_.bundle_blob}}));
  ASSERT_EQ(done.status, 200) << done.body;
  EXPECT_EQ(send(submitter, {"GET", "/v1/blobs/" + beta_.bundle_blob, "", {}}).status, 200);
  // A worker of alpha may not register beta's blob as an artifact either.
  const Response artifact = send(
      tokens_["worker"], json_call("POST", "/v1/worker/jobs/" + alpha_.running_job + "/artifacts",
                                   {{"lease_id", alpha_.lease_id},
                                    {"stage", "ingest"},
                                    {"name", "c.txt"},
                                    {"blob", beta_.extra_blob}}));
  EXPECT_EQ(artifact.status, 404) << artifact.body;
}

TEST_F(AuthorizationTest, ATokenOverItsRateGets429WithRetryAfterWhileOthersAreServed) {
  double now_s = 1000.0;
  HandlerOptions options;
  options.rate_limit.rate_per_s = 2.0;
  options.rate_limit.burst = 3.0;
  options.monotonic_s = [&] { return now_s; };
  HttpHandler limited(*store_, options);
  auto get = [&](const std::string& token, const std::string& target) {
    Request request;
    request.method = "GET";
    request.target = target;
    if (!token.empty()) request.headers.set("Authorization", "Bearer " + token);
    return limited.handle(request);
  };
  const std::string viewer = tokens_["viewer"];
  for (int i = 0; i < 3; ++i) EXPECT_EQ(get(viewer, "/v1/jobs").status, 200) << i;
  const Response refused = get(viewer, "/v1/jobs");
  EXPECT_EQ(refused.status, 429) << refused.body;
  EXPECT_EQ(error_code_of(refused), "rate_limited");
  EXPECT_EQ(refused.headers.get("Retry-After"), "1");  // 0.5 s to the next request, rounded up
  // Another token, and the open routes, are not slowed by it.
  EXPECT_EQ(get(tokens_["submitter"], "/v1/jobs").status, 200);
  EXPECT_EQ(get("", "/healthz").status, 200);
  // A bad token is refused as unknown (401), not counted against anyone.
  EXPECT_EQ(get("no-such-token", "/v1/jobs").status, 401);
  now_s += 0.5;  // one request's worth at 2/s
  EXPECT_EQ(get(viewer, "/v1/jobs").status, 200);
  EXPECT_EQ(get(viewer, "/v1/jobs").status, 429);
}

}  // namespace
}  // namespace keel::server::testing
