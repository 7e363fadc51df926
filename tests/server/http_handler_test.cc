// Cross-cutting behaviour of the pure handler: auth, routing, error bodies, 500s, /metrics.
#include "server/http_handler.h"

#include "tests/server/handler_fixture.h"

namespace keel::server::testing {
namespace {

TEST_F(HandlerTest, HealthAndMetricsNeedNoToken) {
  Response health = call("GET", "/healthz", "", {}, false);
  ASSERT_EQ(health.status, 200);
  EXPECT_EQ(json_of(health)["status"], "ok");
  EXPECT_EQ(call("GET", "/metrics", "", {}, false).status, 200);
}

TEST_F(HandlerTest, V1NeedsAKnownBearerToken) {
  for (const auto& header :
       std::vector<std::map<std::string, std::string>>{{},
                                                       {{"Authorization", "Bearer wrong"}},
                                                       {{"Authorization", "Basic " + token_}},
                                                       {{"Authorization", "Bearer "}},
                                                       {{"Authorization", token_}}}) {
    Response response = call("GET", "/v1/jobs", "", header, false);
    EXPECT_EQ(response.status, 401);
    EXPECT_EQ(error_code_of(response), "unauthorized");
    EXPECT_EQ(response.headers.get("WWW-Authenticate"), "Bearer");
  }
  // Unknown /v1 routes do not reveal themselves before auth.
  EXPECT_EQ(call("GET", "/v1/nothing", "", {}, false).status, 401);
  EXPECT_EQ(call("GET", "/v1/jobs", "", {{"Authorization", "bearer " + token_}}, false).status,
            200);
}

TEST_F(HandlerTest, UnknownRoutesAndMethods) {
  Response unknown = call("GET", "/v1/nothing");
  EXPECT_EQ(unknown.status, 404);
  EXPECT_EQ(error_code_of(unknown), "not_found");
  Response wrong_method = call("DELETE", "/v1/jobs");
  EXPECT_EQ(wrong_method.status, 405);
  EXPECT_EQ(wrong_method.headers.get("Allow"), "POST, GET");
  EXPECT_EQ(call("GET", "no-slash").status, 400);
  EXPECT_EQ(call("GET", "/v1/jobs/%zz").status, 400);
}

TEST_F(HandlerTest, EveryErrorHasTheErrorBody) {
  for (const Response& response :
       {call("GET", "/v1/jobs/x"), call("POST", "/v1/jobs", "[1,2]"), call("POST", "/v1/jobs", ""),
        call("GET", "/v1/jobs", "", {}, false)}) {
    EXPECT_GE(response.status, 400);
    auto body = json_of(response);
    EXPECT_TRUE(body["error"]["code"].is_string());
    EXPECT_TRUE(body["error"]["message"].is_string());
    EXPECT_FALSE(body["error"]["message"].get<std::string>().empty());
  }
}

TEST_F(HandlerTest, BodyLimitsDependOnTheRoute) {
  EXPECT_EQ(handler_->body_limit("PUT", "/v1/uploads/u_1"),
            1u << 20);  // max_chunk_bytes in the fixture
  EXPECT_EQ(handler_->body_limit("POST", "/v1/jobs"), 1u << 20);
  HandlerOptions options;
  options.max_chunk_bytes = 5000;
  options.max_json_bytes = 100;
  HttpHandler small(*store_, options);
  EXPECT_EQ(small.body_limit("PUT", "/v1/uploads/u_1"), 5000u);
  EXPECT_EQ(small.body_limit("POST", "/v1/uploads/u_1/complete"), 100u);
  EXPECT_EQ(small.body_limit("PUT", "/v1/jobs"), 100u);
}

TEST_F(HandlerTest, MetricsCountAnswersByClassAndShowStoreFigures) {
  create_mission("m1");  // upload: 201 + 1 PUT 200 + complete 200; mission 201
  call("GET", "/v1/jobs/nope");
  call("GET", "/v1/jobs/nope");
  call("GET", "/v1/jobs", "", {}, false);
  Response metrics = call("GET", "/metrics", "", {}, false);
  ASSERT_EQ(metrics.status, 200);
  const std::string& text = metrics.body;
  EXPECT_EQ(metrics.headers.get("Content-Type"), "text/plain; version=0.0.4; charset=utf-8");
  EXPECT_NE(text.find("# TYPE keel_http_requests_total counter\n"), std::string::npos);
  EXPECT_NE(text.find("keel_http_requests_total{code=\"2xx\"} 4\n"), std::string::npos) << text;
  EXPECT_NE(text.find("keel_http_requests_total{code=\"4xx\"} 3\n"), std::string::npos) << text;
  EXPECT_NE(text.find("keel_missions 1\n"), std::string::npos) << text;
  EXPECT_NE(text.find("keel_blobs 1\n"), std::string::npos) << text;
  EXPECT_NE(text.find("keel_jobs{state=\"queued\"} 0\n"), std::string::npos) << text;
  EXPECT_NE(text.find("keel_workers_alive 3\n"), std::string::npos) << text;
  // Every sample line belongs to a family announced with HELP and TYPE.
  std::istringstream lines(text);
  std::string line, family;
  while (std::getline(lines, line)) {
    if (line.rfind("# TYPE ", 0) == 0) family = line.substr(7, line.find(' ', 7) - 7);
    if (line.empty() || line[0] == '#') continue;
    EXPECT_EQ(line.rfind(family, 0), 0u) << line;
  }
}

// Delegates to a real store but throws a plain std::runtime_error for job "boom".
class ThrowingStore : public storage::Store {
 public:
  explicit ThrowingStore(storage::Store& inner) : inner_(inner) {}
  proto::Job get_job(const std::string& id) override {
    if (id == "boom") throw std::runtime_error("disk on fire");
    return inner_.get_job(id);
  }
  std::optional<proto::TokenInfo> check_token(const std::string& token) override {
    return inner_.check_token(token);
  }
  // Everything else is not reached by this test.
  proto::Upload create_upload(const proto::UploadRequest& r) override {
    return inner_.create_upload(r);
  }
  proto::Upload get_upload(const std::string& id) override { return inner_.get_upload(id); }
  proto::Upload append_upload(const std::string& id, int64_t o, const char* d, size_t s) override {
    return inner_.append_upload(id, o, d, s);
  }
  std::string complete_upload(const std::string& id, const std::string& sha) override {
    return inner_.complete_upload(id, sha);
  }
  void delete_upload(const std::string& id) override { inner_.delete_upload(id); }
  bool has_blob(const std::string& sha) override { return inner_.has_blob(sha); }
  int64_t blob_size(const std::string& sha) override { return inner_.blob_size(sha); }
  std::filesystem::path blob_path(const std::string& sha) override { return inner_.blob_path(sha); }
  std::string put_blob(const std::string& bytes) override { return inner_.put_blob(bytes); }
  proto::Mission create_mission(const proto::MissionRequest& r) override {
    return inner_.create_mission(r);
  }
  proto::Mission get_mission(const std::string& id) override { return inner_.get_mission(id); }
  std::vector<proto::Mission> list_missions(const std::string& p, const std::string& pr) override {
    return inner_.list_missions(p, pr);
  }
  proto::Job create_job(const proto::JobRequest& r, const std::string& k, bool* c) override {
    return inner_.create_job(r, k, c);
  }
  std::vector<proto::Job> list_jobs(const storage::JobFilter& f) override {
    return inner_.list_jobs(f);
  }
  proto::Job cancel_job(const std::string& id) override { return inner_.cancel_job(id); }
  proto::Job retry_job(const std::string& id) override { return inner_.retry_job(id); }
  proto::Batch create_batch(const proto::ReprocessRequest& r) override {
    return inner_.create_batch(r);
  }
  proto::Batch get_batch(const std::string& id) override { return inner_.get_batch(id); }
  proto::Job release_job(const std::string& id, const std::string& l) override {
    return inner_.release_job(id, l);
  }
  int requeue_expired_leases() override { return inner_.requeue_expired_leases(); }
  std::optional<proto::Lease> lease_job(const proto::LeaseRequest& r) override {
    return inner_.lease_job(r);
  }
  proto::HeartbeatReply heartbeat(const std::string& id, const proto::Heartbeat& b) override {
    return inner_.heartbeat(id, b);
  }
  proto::Artifact add_artifact(const std::string& id,
                               const proto::ArtifactRegistration& r) override {
    return inner_.add_artifact(id, r);
  }
  void complete_stage(const std::string& id, const std::string& s,
                      const proto::StageCompletion& c) override {
    inner_.complete_stage(id, s, c);
  }
  proto::Job finish_job(const std::string& id, const proto::JobFinish& f, bool ok) override {
    return inner_.finish_job(id, f, ok);
  }
  std::vector<proto::Artifact> list_artifacts(const std::string& id) override {
    return inner_.list_artifacts(id);
  }
  proto::Artifact get_artifact(const std::string& id) override { return inner_.get_artifact(id); }
  void append_log(const std::string& id, const std::vector<std::string>& l) override {
    inner_.append_log(id, l);
  }
  proto::LogPage read_log(const std::string& id, int64_t from, int limit) override {
    return inner_.read_log(id, from, limit);
  }
  proto::TokenInfo add_token(const std::string& t, const storage::TokenSpec& s) override {
    return inner_.add_token(t, s);
  }
  std::vector<proto::TokenInfo> list_tokens() override { return inner_.list_tokens(); }
  proto::TokenInfo revoke_token(const std::string& id) override { return inner_.revoke_token(id); }
  int64_t token_count() override { return inner_.token_count(); }
  std::vector<proto::Project> list_projects() override { return inner_.list_projects(); }
  proto::Project ensure_project(const std::string& n) override { return inner_.ensure_project(n); }
  proto::Project set_project_quota(const std::string& n, int64_t q) override {
    return inner_.set_project_quota(n, q);
  }
  int64_t project_usage(const std::string& n) override { return inner_.project_usage(n); }
  bool project_has_blob(const std::string& n, const std::string& b) override {
    return inner_.project_has_blob(n, b);
  }
  std::unique_ptr<storage::Subscription> subscribe(storage::ChangeListener l) override {
    return inner_.subscribe(std::move(l));
  }
  proto::QueueSummary queue_summary() override { return inner_.queue_summary(); }
  storage::Metrics metrics() override { return inner_.metrics(); }

 private:
  storage::Store& inner_;
};

TEST_F(HandlerTest, UnexpectedExceptionGives500AndTheNextRequestIsServed) {
  ThrowingStore throwing(*store_);
  HttpHandler handler(throwing);
  Request boom;
  boom.method = "GET";
  boom.target = "/v1/jobs/boom";
  boom.headers.set("Authorization", "Bearer " + token_);
  Response response = handler.handle(boom);
  EXPECT_EQ(response.status, 500);
  EXPECT_EQ(error_code_of(response), "internal");
  EXPECT_EQ(handler.counters().by_class(5), 1);

  Request next = boom;
  next.target = "/v1/jobs";
  EXPECT_EQ(handler.handle(next).status, 200);
  next.target = "/v1/jobs/other";
  EXPECT_EQ(handler.handle(next).status, 404);
}

}  // namespace
}  // namespace keel::server::testing
