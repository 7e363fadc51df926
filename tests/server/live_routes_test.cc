// Live routes: GET /v1/events (server-sent events), the long-poll lease, lease release,
// batches, the queue summary and project scoping, first through the pure handler (driving
// the streams by hand), then through real sockets.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>

#include "server/http_server.h"
#include "tests/server/handler_fixture.h"
#include "tests/server/raw_http_client.h"

namespace keel::server::testing {
namespace {

using namespace std::chrono_literals;

class LiveRoutesTest : public HandlerTest {
 protected:
  std::string add_token(proto::Role role, const std::string& project) {
    const std::string token = "tok-" + proto::to_string(role) + "-" + project;
    storage::TokenSpec spec;
    spec.role = role;
    spec.project = project;
    store_->add_token(token, spec);
    return token;
  }
  Response call_as(const std::string& token, const std::string& method, const std::string& target,
                   const std::string& body = "") {
    Request request;
    request.method = method;
    request.target = target;
    request.body = body;
    request.headers.set("Authorization", "Bearer " + token);
    return handler_->handle(request);
  }
  nlohmann::json mission_in(const std::string& project, const std::string& name) {
    const std::string blob = upload(valid_bundle(name));
    Response response =
        post("/v1/missions", {{"name", name}, {"bundle_blob", blob}, {"project", project}});
    EXPECT_EQ(response.status, 201) << response.body;
    return json_of(response);
  }
};

TEST_F(LiveRoutesTest, EventStreamSendsHelloThenJobAndLogEventsOfItsProjectOnly) {
  const std::string viewer = add_token(proto::Role::kViewer, "harbour");
  Response response = call_as(viewer, "GET", "/v1/events");
  ASSERT_EQ(response.status, 200) << response.body;
  ASSERT_TRUE(response.stream);
  EXPECT_EQ(response.headers.get("Content-Type"), "text/event-stream");
  std::atomic<int> wakes{0};
  response.stream->start([&] { ++wakes; });
  bool ended = true;
  std::string out = response.stream->take(false, ended);
  EXPECT_FALSE(ended);
  EXPECT_EQ(out.rfind("event: hello\ndata: {\"server_time_ms\":", 0), 0u) << out;

  const nlohmann::json other = mission_in("dock", "dock-pier");
  const nlohmann::json other_job = create_job(other["id"]);
  call("POST", "/v1/jobs/" + other_job["id"].get<std::string>() + "/cancel");
  EXPECT_EQ(wakes.load(), 0) << "another project's change must not even wake the stream";
  EXPECT_EQ(response.stream->take(false, ended), "");

  const nlohmann::json mine = mission_in("harbour", "harbour-pier");
  const nlohmann::json job = create_job(mine["id"]);
  EXPECT_GE(wakes.load(), 1);
  out = response.stream->take(false, ended);
  const std::string prefix = "event: job\ndata: ";
  ASSERT_EQ(out.rfind(prefix, 0), 0u) << out;
  const nlohmann::json event = nlohmann::json::parse(out.substr(prefix.size()));
  EXPECT_EQ(event["id"], job["id"]);
  EXPECT_EQ(event["state"], "queued");
  EXPECT_EQ(event["project"], "harbour");
  EXPECT_EQ(event["mission_name"], "harbour-pier");

  // A heartbeat with log lines: one job event (coalesced) and one log event.
  const nlohmann::json lease = this->lease();
  ASSERT_EQ(lease["job"]["id"], job["id"]);
  response.stream->take(false, ended);
  for (double progress : {0.25, 0.5})
    post("/v1/worker/jobs/" + job["id"].get<std::string>() + "/heartbeat",
         {{"lease_id", lease["lease_id"]}, {"stage", "ingest"}, {"progress", progress},
          {"log", {"line"}}});
  out = response.stream->take(false, ended);
  EXPECT_EQ(out.find("event: job"), out.rfind("event: job")) << "coalesced: " << out;
  EXPECT_NE(out.find("\"progress\":0.5"), std::string::npos) << out;
  EXPECT_NE(out.find("event: log\ndata: {\"job_id\":\"" + job["id"].get<std::string>() + "\"}"),
            std::string::npos)
      << out;

  out = response.stream->take(true, ended);
  EXPECT_TRUE(ended) << "the server stopping ends the stream";
}

TEST_F(LiveRoutesTest, EventStreamOfOneJobAndOfAnotherProjectsJob) {
  const nlohmann::json a = create_job(create_mission("a")["id"]);
  const nlohmann::json b = create_job(create_mission("b")["id"]);
  Response response = call("GET", "/v1/events?job_id=" + b["id"].get<std::string>());
  ASSERT_TRUE(response.stream);
  response.stream->start([] {});
  bool ended = false;
  response.stream->take(false, ended);
  call("POST", "/v1/jobs/" + a["id"].get<std::string>() + "/cancel");
  call("POST", "/v1/jobs/" + b["id"].get<std::string>() + "/cancel");
  const std::string out = response.stream->take(false, ended);
  EXPECT_EQ(out.find(a["id"].get<std::string>()), std::string::npos) << out;
  EXPECT_NE(out.find("\"state\":\"canceled\""), std::string::npos) << out;

  const std::string stranger = add_token(proto::Role::kViewer, "dock");
  Response refused = call_as(stranger, "GET", "/v1/events?job_id=" + b["id"].get<std::string>());
  EXPECT_EQ(refused.status, 404);
  EXPECT_FALSE(refused.stream);
}

TEST_F(LiveRoutesTest, LongPollLeaseIsWokenByANewJobAndAnswers204AtItsDeadline) {
  Response waiting =
      post("/v1/worker/lease", {{"worker", "w:1"}, {"lease_seconds", 30}, {"wait_seconds", 5}});
  ASSERT_TRUE(waiting.pending) << waiting.status << " " << waiting.body;
  std::atomic<int> wakes{0};
  waiting.pending->start([&] { ++wakes; });
  EXPECT_GE(wakes.load(), 1) << "the first try is asked for at once";
  EXPECT_FALSE(waiting.pending->poll(false));
  const int before = wakes.load();
  const nlohmann::json job = create_job(create_mission("m")["id"]);
  EXPECT_GT(wakes.load(), before);
  std::optional<Response> answer = waiting.pending->poll(false);
  ASSERT_TRUE(answer);
  EXPECT_EQ(answer->status, 200);
  EXPECT_EQ(json_of(*answer)["job"]["id"], job["id"]);

  Response empty =
      post("/v1/worker/lease", {{"worker", "w:2"}, {"lease_seconds", 30}, {"wait_seconds", 1}});
  ASSERT_TRUE(empty.pending);
  empty.pending->start([] {});
  answer = empty.pending->poll(true);
  ASSERT_TRUE(answer);
  EXPECT_EQ(answer->status, 204);

  Response too_long =
      post("/v1/worker/lease", {{"worker", "w:3"}, {"lease_seconds", 30}, {"wait_seconds", 31}});
  EXPECT_EQ(too_long.status, 400) << too_long.body;
}

TEST_F(LiveRoutesTest, ReleaseQueuesTheJobAtOnceAndFencesTheOldLease) {
  const nlohmann::json job = create_job(create_mission("m")["id"]);
  const nlohmann::json lease = this->lease();
  const std::string path = "/v1/worker/jobs/" + job["id"].get<std::string>();
  Response released = post(path + "/release", {{"lease_id", lease["lease_id"]}});
  ASSERT_EQ(released.status, 200) << released.body;
  EXPECT_EQ(json_of(released)["state"], "queued");
  Response again = post(path + "/release", {{"lease_id", lease["lease_id"]}});
  EXPECT_EQ(again.status, 409);
  EXPECT_EQ(error_code_of(again), "lease_lost");
  Response stale = post(path + "/complete", {{"lease_id", lease["lease_id"]}});
  EXPECT_EQ(stale.status, 409);
  EXPECT_EQ(this->lease()["job"]["attempts"], 2);
}

TEST_F(LiveRoutesTest, ReprocessMakesABatchThatCanBeFollowed) {
  for (const char* name : {"survey-1", "survey-2", "other"}) create_mission(name);
  Response made = post("/v1/reprocess", {{"name_prefix", "survey-"}, {"stages", {"ingest"}}});
  ASSERT_EQ(made.status, 201) << made.body;
  const nlohmann::json body = json_of(made);
  ASSERT_EQ(body["jobs"].size(), 2u);
  EXPECT_EQ(body["jobs"][0]["mission_name"], "survey-1");
  const std::string batch_id = body["batch"]["id"];
  EXPECT_EQ(body["jobs"][1]["batch_id"], batch_id);
  Response batch = call("GET", "/v1/batches/" + batch_id);
  ASSERT_EQ(batch.status, 200) << batch.body;
  EXPECT_EQ(json_of(batch)["jobs"], 2);
  EXPECT_EQ(json_of(batch)["jobs_by_state"]["queued"], 2);
  Response listed = call("GET", "/v1/jobs?batch_id=" + batch_id);
  EXPECT_EQ(json_of(listed)["jobs"].size(), 2u);
  Response queue = call("GET", "/v1/queue");
  ASSERT_EQ(queue.status, 200);
  EXPECT_EQ(json_of(queue)["jobs_by_state"]["queued"], 2);

  const std::string stranger = add_token(proto::Role::kSubmitter, "dock");
  EXPECT_EQ(call_as(stranger, "GET", "/v1/batches/" + batch_id).status, 404);
}

// Over 1,000 jobs the answer is the batch alone (made in one transaction, answered at once);
// the jobs are there to page through.
TEST_F(LiveRoutesTest, LargeBatchIsAnsweredWithoutItsJobs) {
  for (int i = 0; i < 1001; ++i) create_mission("survey-" + std::to_string(i));
  Response made = post("/v1/reprocess", {{"name_prefix", "survey-"}, {"stages", {"ingest"}}});
  ASSERT_EQ(made.status, 201) << made.body;
  const nlohmann::json body = json_of(made);
  EXPECT_EQ(body["batch"]["jobs"], 1001);
  EXPECT_TRUE(body["jobs"].empty());
  const std::string batch_id = body["batch"]["id"];
  EXPECT_EQ(json_of(call("GET", "/v1/batches/" + batch_id))["jobs_by_state"]["queued"], 1001);
  EXPECT_EQ(json_of(call("GET", "/v1/jobs?limit=5000&batch_id=" + batch_id))["jobs"].size(), 1001u);
}

TEST_F(LiveRoutesTest, AnotherProjectsObjectsAnswer404AndListsLeaveThemOut) {
  const nlohmann::json theirs = mission_in("harbour", "pier");
  const nlohmann::json job = create_job(theirs["id"]);
  const std::string stranger = add_token(proto::Role::kSubmitter, "dock");
  const std::string id = job["id"];
  for (const std::string& target :
       {"/v1/jobs/" + id, "/v1/jobs/" + id + "/log", "/v1/jobs/" + id + "/artifacts",
        "/v1/missions/" + theirs["id"].get<std::string>()}) {
    Response response = call_as(stranger, "GET", target);
    EXPECT_EQ(response.status, 404) << target;
    EXPECT_EQ(response.body.find("harbour"), std::string::npos) << response.body;
  }
  EXPECT_EQ(call_as(stranger, "POST", "/v1/jobs/" + id + "/cancel").status, 404);
  EXPECT_TRUE(json_of(call_as(stranger, "GET", "/v1/jobs"))["jobs"].empty());
  EXPECT_TRUE(json_of(call_as(stranger, "GET", "/v1/missions"))["missions"].empty());
  // A job for their mission, made with the stranger's token: the mission "does not exist".
  Response made = call_as(stranger, "POST", "/v1/jobs",
                          nlohmann::json{{"mission_id", theirs["id"]}, {"stages", {"ingest"}}}.dump());
  EXPECT_EQ(made.status, 404) << made.body;
  // Naming another project in a request is the same as naming a project that does not exist.
  Response upload = call_as(stranger, "POST", "/v1/uploads",
                            nlohmann::json{{"name", "x"}, {"size", 1}, {"project", "harbour"}}.dump());
  EXPECT_EQ(upload.status, 404);
  EXPECT_EQ(call_as("tok-nobody", "GET", "/v1/jobs").status, 401);
}

// --- through real sockets ---

class LiveSocketTest : public HandlerTest {
 protected:
  void SetUp() override {
    HandlerTest::SetUp();
    ServerOptions options;
    options.port = 0;
    options.threads = 2;
    options.shutdown_grace = 10000ms;
    server_ = std::make_unique<HttpServer>(*handler_, options);
    server_->start();
  }
  void TearDown() override { server_->stop(); }
  std::unique_ptr<HttpServer> server_;
};

TEST_F(LiveSocketTest, WaitingWorkerGetsTheJobQueuedWhileItWaits) {
  const std::string mission = create_mission("m")["id"];
  RawClient worker(server_->port(), 15000);
  ASSERT_TRUE(worker.send(http_request(
      "POST", "/v1/worker/lease", token_,
      nlohmann::json{{"worker", "w:1"}, {"lease_seconds", 30}, {"wait_seconds", 20}}.dump())));
  std::this_thread::sleep_for(300ms);
  const nlohmann::json job = create_job(mission);
  std::optional<HttpReply> reply = worker.read_reply();
  ASSERT_TRUE(reply) << "no answer before the client's 15 s read timeout: not woken";
  EXPECT_EQ(reply->status, 200);
  EXPECT_EQ(nlohmann::json::parse(reply->body)["job"]["id"], job["id"]);
  // The connection stays usable (keep-alive) after a long poll.
  reply = worker.exchange(http_request("GET", "/v1/queue", token_));
  ASSERT_TRUE(reply);
  EXPECT_EQ(reply->status, 200);
}

TEST_F(LiveSocketTest, WorkerThatHungUpIsNotGivenTheJob) {
  const std::string mission = create_mission("m")["id"];
  {
    RawClient worker(server_->port());
    ASSERT_TRUE(worker.send(http_request(
        "POST", "/v1/worker/lease", token_,
        nlohmann::json{{"worker", "gone:1"}, {"lease_seconds", 30}, {"wait_seconds", 20}}.dump())));
    std::this_thread::sleep_for(200ms);
  }  // closed while waiting
  std::this_thread::sleep_for(200ms);
  const nlohmann::json job = create_job(mission);
  std::this_thread::sleep_for(300ms);
  EXPECT_EQ(store_->get_job(job["id"]).state, proto::JobState::kQueued);
}

TEST_F(LiveSocketTest, EventStreamDeliversChangesAsChunks) {
  RawClient watcher(server_->port(), 10000);
  ASSERT_TRUE(watcher.send(http_request("GET", "/v1/events", token_)));
  auto head = watcher.read_until("\r\n\r\n");
  ASSERT_TRUE(head);
  EXPECT_NE(head->find("200"), std::string::npos);
  EXPECT_NE(head->find("Transfer-Encoding: chunked"), std::string::npos) << *head;
  EXPECT_NE(head->find("text/event-stream"), std::string::npos) << *head;
  ASSERT_TRUE(watcher.read_until("event: hello"));
  const nlohmann::json job = create_job(create_mission("m")["id"]);
  auto event = watcher.read_until("\"id\":\"" + job["id"].get<std::string>() + "\"");
  ASSERT_TRUE(event) << "no job event before the 10 s read timeout";
  EXPECT_NE(event->find("event: job"), std::string::npos);
}

TEST_F(LiveSocketTest, StopEndsOpenStreamsAndLongPolls) {
  RawClient watcher(server_->port(), 10000);
  ASSERT_TRUE(watcher.send(http_request("GET", "/v1/events", token_)));
  ASSERT_TRUE(watcher.read_until("event: hello"));
  RawClient worker(server_->port(), 10000);
  ASSERT_TRUE(worker.send(http_request(
      "POST", "/v1/worker/lease", token_,
      nlohmann::json{{"worker", "w:1"}, {"lease_seconds", 30}, {"wait_seconds", 30}}.dump())));
  std::this_thread::sleep_for(200ms);
  const auto started = std::chrono::steady_clock::now();
  server_->stop();
  // The grace period is 10 s: a stop that waits for it did not end the live answers.
  EXPECT_LT(std::chrono::steady_clock::now() - started, 8000ms)
      << "stop waited for the grace period instead of ending the live answers";
  std::optional<HttpReply> reply = worker.read_reply();
  ASSERT_TRUE(reply);
  EXPECT_EQ(reply->status, 204);
  EXPECT_TRUE(watcher.read_until("0\r\n\r\n")) << "the stream ends with the last chunk";
}

}  // namespace
}  // namespace keel::server::testing
