// Missions and jobs through the Store: creation, listing, idempotency, cancel, errors.
#include <gtest/gtest.h>

#include "core/sha256.h"
#include "store_fixture.h"

namespace keel::storage {
namespace {

using testing::StoreTest;

// Runs `call`, expects exception type E and returns its message.
template <typename E, typename Call>
std::string message_of(Call call) {
  try {
    call();
  } catch (const E& error) {
    return error.what();
  }
  ADD_FAILURE() << "expected an exception";
  return "";
}

bool has_hex_suffix(const std::string& id, const std::string& prefix) {
  if (id.rfind(prefix, 0) != 0 || id.size() < prefix.size() + 16) return false;
  return id.find_first_not_of("0123456789abcdef", prefix.size()) == std::string::npos;
}

using MissionTest = StoreTest;
using JobTest = StoreTest;

TEST_P(MissionTest, CreateGetAndListByPrefix) {
  const proto::Mission a = make_mission("bridge-01");
  clock_.advance_ms(10);
  const proto::Mission b = make_mission("bridge-02");
  clock_.advance_ms(10);
  const proto::Mission c = make_mission("hull-7");
  EXPECT_TRUE(has_hex_suffix(a.id, "m_")) << a.id;
  EXPECT_NE(a.id, b.id);
  const proto::Mission got = store_->get_mission(b.id);
  EXPECT_EQ(got.name, "bridge-02");
  EXPECT_EQ(got.bundle_blob, b.bundle_blob);
  EXPECT_EQ(got.created_at_ms, clock_.now_ms() - 10);
  const auto bridges = store_->list_missions("bridge-");
  ASSERT_EQ(bridges.size(), 2u);
  EXPECT_EQ(bridges[0].id, b.id);  // newest first
  EXPECT_EQ(bridges[1].id, a.id);
  EXPECT_EQ(store_->list_missions().size(), 3u);
  EXPECT_TRUE(store_->list_missions("Bridge").empty());  // case-sensitive
  EXPECT_TRUE(store_->list_missions("%").empty());       // no LIKE wildcards
  EXPECT_EQ(store_->list_missions("hull")[0].id, c.id);
}

TEST_P(MissionTest, CadBlobAndErrors) {
  proto::MissionRequest request{"hull", store_->put_blob("tar"), store_->put_blob("ply"),
                                "ship.ply"};
  EXPECT_EQ(store_->get_mission(store_->create_mission(request).id).cad_name, "ship.ply");
  const std::string missing = std::string(64, 'a');
  request.cad_blob = missing;
  EXPECT_NE(message_of<NotFound>([&] { store_->create_mission(request); }).find(missing),
            std::string::npos);
  request.cad_blob = "";
  request.cad_name = "";
  request.bundle_blob = "xyz";
  EXPECT_NE(message_of<Invalid>([&] { store_->create_mission(request); }).find("bundle_blob"),
            std::string::npos);
  request.bundle_blob = store_->put_blob("tar");
  request.name = "";
  EXPECT_THROW(store_->create_mission(request), Invalid);
  EXPECT_NE(message_of<NotFound>([&] {
              store_->get_mission("m_0000000000000000");
            }).find("m_0000000000000000"),
            std::string::npos);
}

TEST_P(JobTest, CreateAndGet) {
  const proto::Mission mission = make_mission();
  proto::JobRequest request = job_request(mission);
  request.options = {{"map", {{"voxel_m", 0.05}}}};
  bool created = false;
  const proto::Job job = store_->create_job(request, "", &created);
  EXPECT_TRUE(created);
  EXPECT_TRUE(has_hex_suffix(job.id, "j_")) << job.id;
  const proto::Job got = store_->get_job(job.id);
  EXPECT_EQ(got.mission_id, mission.id);
  EXPECT_EQ(got.state, proto::JobState::kQueued);
  EXPECT_EQ(got.stages, (std::vector<std::string>{"ingest", "refine", "map"}));
  EXPECT_EQ(got.options["map"]["voxel_m"].get<double>(), 0.05);
  EXPECT_EQ(got.attempts, 0);
  EXPECT_EQ(got.created_at_ms, clock_.now_ms());
  EXPECT_EQ(got.started_at_ms, 0);
  EXPECT_TRUE(got.completed_stages.empty());
}

TEST_P(JobTest, BadRequestsAreInvalidOrNotFound) {
  const proto::Mission mission = make_mission();
  EXPECT_THROW(store_->create_job(job_request(mission, {}), ""), Invalid);
  EXPECT_THROW(store_->create_job(job_request(mission, {"map", "map"}), ""), Invalid);
  EXPECT_NE(message_of<Invalid>([&] {
              store_->create_job(job_request(mission, {"bake"}), "");
            }).find("bake"),
            std::string::npos);
  proto::JobRequest request = job_request(mission);
  request.mission_id = "m_ffffffffffffffff";
  EXPECT_NE(
      message_of<NotFound>([&] { store_->create_job(request, ""); }).find("m_ffffffffffffffff"),
      std::string::npos);
  EXPECT_NE(message_of<NotFound>([&] {
              store_->get_job("j_0123456789abcdef");
            }).find("j_0123456789abcdef"),
            std::string::npos);
}

TEST_P(JobTest, IdempotencyKeyReturnsFirstJob) {
  const proto::Mission mission = make_mission();
  bool created = false;
  const proto::Job first = store_->create_job(job_request(mission), "key-1", &created);
  EXPECT_TRUE(created);
  const proto::Job again = store_->create_job(job_request(mission), "key-1", &created);
  EXPECT_FALSE(created);
  EXPECT_EQ(again.id, first.id);
  const proto::Job other = store_->create_job(job_request(mission), "key-2", &created);
  EXPECT_TRUE(created);
  EXPECT_NE(other.id, first.id);
  // Without a key every call makes a job.
  EXPECT_NE(store_->create_job(job_request(mission), "").id,
            store_->create_job(job_request(mission), "").id);
  EXPECT_EQ(store_->list_jobs({}).size(), 4u);
  // The same key for a different request is a client bug, not a repeat.
  EXPECT_THROW(store_->create_job(job_request(mission, {"ingest"}), "key-1"), Conflict);
}

TEST_P(JobTest, ListNewestFirstWithFilters) {
  const proto::Mission m1 = make_mission("a");
  const proto::Mission m2 = make_mission("b");
  std::vector<std::string> ids;
  for (int i = 0; i < 5; ++i) {
    ids.push_back(store_->create_job(job_request(i % 2 ? m2 : m1), "").id);
    clock_.advance_ms(1);
  }
  store_->cancel_job(ids[1]);
  const auto all = store_->list_jobs({});
  ASSERT_EQ(all.size(), 5u);
  for (size_t i = 0; i < 5; ++i) EXPECT_EQ(all[i].id, ids[4 - i]);
  const auto of_m2 = store_->list_jobs({std::nullopt, m2.id});
  ASSERT_EQ(of_m2.size(), 2u);
  EXPECT_EQ(of_m2[0].id, ids[3]);
  const auto queued_m2 = store_->list_jobs({proto::JobState::kQueued, m2.id});
  ASSERT_EQ(queued_m2.size(), 1u);
  EXPECT_EQ(queued_m2[0].id, ids[3]);
  const auto canceled = store_->list_jobs({proto::JobState::kCanceled, ""});
  ASSERT_EQ(canceled.size(), 1u);
  EXPECT_EQ(canceled[0].id, ids[1]);
  JobFilter two;
  two.limit = 2;
  EXPECT_EQ(store_->list_jobs(two).size(), 2u);
  EXPECT_THROW(store_->list_jobs({std::nullopt, "", 0}), Invalid);
  const Metrics metrics = store_->metrics();
  EXPECT_EQ(metrics.jobs_by_state[static_cast<int>(proto::JobState::kQueued)], 4);
  EXPECT_EQ(metrics.jobs_by_state[static_cast<int>(proto::JobState::kCanceled)], 1);
  EXPECT_EQ(metrics.missions, 2);
}

TEST_P(JobTest, CancelQueuedAndConflictWhenFinished) {
  const proto::Job job = store_->create_job(job_request(make_mission()), "");
  clock_.advance_ms(5);
  const proto::Job canceled = store_->cancel_job(job.id);
  EXPECT_EQ(canceled.state, proto::JobState::kCanceled);
  EXPECT_EQ(canceled.finished_at_ms, clock_.now_ms());
  EXPECT_NE(message_of<Conflict>([&] { store_->cancel_job(job.id); }).find(job.id),
            std::string::npos);
  EXPECT_FALSE(store_->lease_job({"w", 30}).has_value());  // canceled jobs are not leased
  EXPECT_THROW(store_->retry_job(store_->create_job(job_request(make_mission("x")), "").id),
               Conflict);  // queued: nothing to retry
}

TEST_P(JobTest, LogsInPagesWithSeq) {
  const proto::Job job = store_->create_job(job_request(make_mission()), "");
  store_->append_log(job.id, {"a", "b", "c"});
  clock_.advance_ms(7);
  store_->append_log(job.id, {"d"});
  const proto::LogPage first = store_->read_log(job.id, 0, 2);
  ASSERT_EQ(first.lines.size(), 2u);
  EXPECT_EQ(first.lines[0].seq, 0);
  EXPECT_EQ(first.lines[1].text, "b");
  EXPECT_EQ(first.next, 2);
  const proto::LogPage rest = store_->read_log(job.id, first.next, 100);
  ASSERT_EQ(rest.lines.size(), 2u);
  EXPECT_EQ(rest.lines[1].seq, 3);
  EXPECT_EQ(rest.lines[1].text, "d");
  EXPECT_EQ(rest.lines[1].t_ms, clock_.now_ms());
  EXPECT_EQ(rest.next, 4);
  const proto::LogPage none = store_->read_log(job.id, 4, 100);
  EXPECT_TRUE(none.lines.empty());
  EXPECT_EQ(none.next, 4);
  EXPECT_THROW(store_->read_log("j_0000000000000000", 0, 10), NotFound);
  EXPECT_THROW(store_->append_log("j_0000000000000000", {"x"}), NotFound);
  EXPECT_THROW(store_->read_log(job.id, -1, 10), Invalid);
}

TEST_P(JobTest, TokensStoredAsHashOnly) {
  const std::string token = "kt_5f2b9c0d1e4a7788aa01bb02cc03dd04";
  EXPECT_EQ(store_->token_count(), 0);
  store_->add_token(token, admin_token("first"));
  store_->add_token(token, admin_token("first"));  // idempotent
  EXPECT_EQ(store_->token_count(), 1);
  EXPECT_TRUE(store_->check_token(token));
  EXPECT_FALSE(store_->check_token(token + "x"));
  EXPECT_FALSE(store_->check_token(""));
  EXPECT_THROW(store_->add_token("", admin_token("empty")), Invalid);
  store_.reset();  // close, so the WAL is checkpointed into keel.db
  std::string bytes;
  if (postgres()) {
    // Every stored column of every token row, as PostgreSQL prints them.
    pqxx::connection connection(database_url_);
    pqxx::nontransaction work(connection);
    for (const auto& row : work.exec("SELECT t::text FROM api_tokens t"))
      bytes += row[0].as<std::string>();
  } else {
    for (const char* file : {"keel.db", "keel.db-wal"})
      bytes += testing::read_file(dir_.path() / file);
  }
  EXPECT_EQ(bytes.find(token), std::string::npos);
  EXPECT_EQ(bytes.find(token.substr(3, 20)), std::string::npos);
  EXPECT_NE(bytes.find(sha256_bytes(token)), std::string::npos);  // its hash is what is kept
  reopen();
  EXPECT_TRUE(store_->check_token(token));
}

KEEL_STORE_TEST_SUITE(MissionTest);
KEEL_STORE_TEST_SUITE(JobTest);

}  // namespace
}  // namespace keel::storage
