// What only PostgreSQL has: several stores (replicas) on one database and blob folder, the
// change feed between them, migrations under concurrent starts, and open_store's errors.
#include <gtest/gtest.h>
#include <sys/mount.h>
#include <unistd.h>

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <set>
#include <thread>

#include "storage/open_store.h"
#include "storage/pg_migrations.h"
#include "store_fixture.h"

namespace keel::storage {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using keel::testing::PgTestServer;

// Collects a subscription's changes; waits for one that matches.
class Heard {
 public:
  explicit Heard(Store& store)
      : subscription_(store.subscribe([this](const Change& change) {
          std::lock_guard<std::mutex> lock(mutex_);
          changes_.push_back(change);
          arrived_.notify_all();
        })) {}
  template <typename Match>
  bool wait_for(Match match, std::chrono::milliseconds timeout = 5000ms) {
    std::unique_lock<std::mutex> lock(mutex_);
    return arrived_.wait_for(lock, timeout, [&] {
      for (const Change& change : changes_)
        if (match(change)) return true;
      return false;
    });
  }
  size_t count(const std::string& job_id, proto::JobState state) {
    std::lock_guard<std::mutex> lock(mutex_);
    size_t n = 0;
    for (const Change& change : changes_)
      n += change.kind == Change::Kind::kJob && change.job_id == job_id && change.state == state;
    return n;
  }

 private:
  std::mutex mutex_;
  std::condition_variable arrived_;
  std::vector<Change> changes_;
  std::unique_ptr<Subscription> subscription_;
};

class PgReplicaTest : public ::testing::Test {
 protected:
  void SetUp() override {
    server_ = PgTestServer::shared();
    if (!server_) GTEST_SKIP() << PgTestServer::reason();
    url_ = server_->create_database();
  }
  std::unique_ptr<Store> replica(Clock clock = system_clock_ms) {
    StoreLocation location;
    location.database_url = url_;
    location.blob_dir = dir_.path() / "shared";
    location.data_dir = dir_.path() / "replica";
    return open_store(location, std::move(clock));
  }
  static proto::Mission mission_in(Store& store, const std::string& project) {
    proto::MissionRequest request;
    request.name = "pier";
    request.project = project;
    request.bundle_blob = store.put_blob("bundle");
    return store.create_mission(request);
  }
  static proto::JobRequest request_for(const proto::Mission& mission) {
    proto::JobRequest request;
    request.mission_id = mission.id;
    request.stages = {"ingest"};
    return request;
  }

  PgTestServer* server_ = nullptr;
  std::string url_;
  testing::TempDir dir_;
};

TEST_F(PgReplicaTest, ChangesOfOneReplicaAreHeardOnAnotherOnceEach) {
  auto a = replica();
  auto b = replica();
  Heard on_a(*a), on_b(*b);
  const proto::Mission mission = mission_in(*a, "harbour");
  const proto::Job job = a->create_job(request_for(mission), "");
  EXPECT_TRUE(on_b.wait_for([&](const Change& c) {
    return c.job_id == job.id && c.project == "harbour" && c.state == proto::JobState::kQueued;
  })) << "B hears the job A queued";
  // B leases it: A hears that; B's own listener hears its change once, not again via LISTEN.
  auto lease = b->lease_job({"w", 30});
  ASSERT_TRUE(lease);
  EXPECT_TRUE(on_a.wait_for(
      [&](const Change& c) { return c.job_id == job.id && c.state == proto::JobState::kRunning; }));
  std::this_thread::sleep_for(300ms);
  EXPECT_EQ(on_b.count(job.id, proto::JobState::kRunning), 1u);
  EXPECT_EQ(on_a.count(job.id, proto::JobState::kQueued), 1u);
}

TEST_F(PgReplicaTest, IdempotencyKeyHoldsAcrossReplicasRacing) {
  auto a = replica();
  auto b = replica();
  const proto::Mission mission = mission_in(*a, "default");
  std::vector<std::string> ids(8);
  std::atomic<int> made{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < 8; ++t)
    threads.emplace_back([&, t] {
      bool created = false;
      ids[t] = (t % 2 ? a : b)->create_job(request_for(mission), "submit-42", &created).id;
      made += created;
    });
  for (auto& thread : threads) thread.join();
  EXPECT_EQ(std::set<std::string>(ids.begin(), ids.end()).size(), 1u);
  EXPECT_EQ(made.load(), 1);
  EXPECT_EQ(a->list_jobs({}).size(), 1u);
}

TEST_F(PgReplicaTest, TwoReplicasLeasingNeverTakeOneJobTwice) {
  auto a = replica();
  auto b = replica();
  const proto::Mission mission = mission_in(*a, "default");
  for (int i = 0; i < 300; ++i) a->create_job(request_for(mission), "");
  std::mutex mutex;
  std::multiset<std::string> taken;
  std::vector<std::thread> threads;
  for (int t = 0; t < 6; ++t)
    threads.emplace_back([&, t] {
      Store& store = t % 2 ? *a : *b;
      while (auto lease = store.lease_job({"w" + std::to_string(t), 60})) {
        std::lock_guard<std::mutex> lock(mutex);
        taken.insert(lease->job.id);
      }
    });
  for (auto& thread : threads) thread.join();
  EXPECT_EQ(taken.size(), 300u);
  EXPECT_EQ(std::set<std::string>(taken.begin(), taken.end()).size(), 300u);
}

// Another replica requeues a lease that expired while its worker was away; the worker's
// late calls change nothing.
TEST_F(PgReplicaTest, AnyReplicaRequeuesExpiredLeases) {
  testing::FakeClock clock;
  auto a = replica(clock.clock());
  auto b = replica(clock.clock());
  const proto::Job job = a->create_job(request_for(mission_in(*a, "default")), "");
  const proto::Lease lease = *a->lease_job({"lost-worker", 30});
  clock.advance_ms(30'000);
  EXPECT_EQ(b->requeue_expired_leases(), 1);
  EXPECT_EQ(a->requeue_expired_leases(), 0);
  EXPECT_THROW(a->heartbeat(job.id, {lease.lease_id, "", 0.5, {}}), LeaseLost);
  const proto::LogPage log = b->read_log(job.id, 0, 10);
  ASSERT_EQ(log.lines.size(), 1u);
  EXPECT_NE(log.lines[0].text.find("lost-worker"), std::string::npos) << log.lines[0].text;
  EXPECT_EQ(b->get_job(job.id).state, proto::JobState::kQueued);
}

TEST_F(PgReplicaTest, FreshDatabaseGetsEveryMigrationAndReplicasStartingTogetherAgree) {
  std::vector<std::unique_ptr<Store>> stores(4);
  std::vector<std::thread> threads;
  std::atomic<int> failures{0};
  for (int i = 0; i < 4; ++i)
    threads.emplace_back([&, i] {
      try {
        stores[i] = replica();
      } catch (const std::exception& error) {
        ADD_FAILURE() << error.what();
        ++failures;
      }
    });
  for (auto& thread : threads) thread.join();
  ASSERT_EQ(failures.load(), 0);
  PgPool pool(url_, 1);
  EXPECT_EQ(pg_schema_version(pool), static_cast<int>(pg_migrations().size()));
  EXPECT_EQ(stores[0]->list_projects().size(), 1u) << "the default project made once";
}

TEST_F(PgReplicaTest, NewerSchemaIsRefusedNamingBothVersions) {
  replica().reset();
  const int newest = static_cast<int>(pg_migrations().size());
  pqxx::connection connection(url_);
  pqxx::nontransaction work(connection);
  work.exec("UPDATE schema_version SET version = " + std::to_string(newest + 1));
  try {
    replica();
    FAIL() << "expected OpenError";
  } catch (const OpenError& error) {
    EXPECT_EQ(error.kind, OpenError::Kind::kSchemaTooNew);
    const std::string message = error.what();
    EXPECT_NE(message.find("schema version " + std::to_string(newest + 1)), std::string::npos)
        << message;
    EXPECT_NE(message.find("newer keel-server"), std::string::npos) << message;
  }
}

// Throws OpenError of `kind` (and returns its message) within `seconds`.
template <typename Open>
std::string open_error(OpenError::Kind kind, Open open, double seconds = 15) {
  const auto start = std::chrono::steady_clock::now();
  try {
    open();
  } catch (const OpenError& error) {
    EXPECT_EQ(static_cast<int>(error.kind), static_cast<int>(kind)) << error.what();
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
              seconds);
    return error.what();
  }
  ADD_FAILURE() << "expected OpenError";
  return "";
}

TEST_F(PgReplicaTest, BadDatabaseUrlsAreClearErrors) {
  StoreLocation location;
  location.data_dir = dir_.path() / "data";
  location.database_url = "mysql://root@db/keel";
  std::string message = open_error(OpenError::Kind::kBadUrl, [&] { open_store(location); });
  EXPECT_NE(message.find("postgresql://"), std::string::npos) << message;

  // Nothing listens there: refused at once.
  location.database_url = "postgresql://keel:secret@127.0.0.1:1/keel";
  message = open_error(OpenError::Kind::kUnreachable, [&] { open_store(location); });
  EXPECT_NE(message.find("127.0.0.1:1"), std::string::npos) << message;
  EXPECT_EQ(message.find("secret"), std::string::npos) << "the password is not shown";

  // The server is there, the database is not.
  location.database_url = server_->url("no_such_database");
  message = open_error(OpenError::Kind::kUnreachable, [&] { open_store(location); });
  EXPECT_NE(message.find("no_such_database"), std::string::npos) << message;

  // A blackholed address: connect_timeout bounds the wait.
  location.database_url = "postgresql://keel@10.255.255.1:5432/keel?connect_timeout=2";
  open_error(
      OpenError::Kind::kUnreachable, [&] { open_store(location); }, 10);
}

TEST_F(PgReplicaTest, UnwritableBlobFolderIsAClearError) {
  const fs::path blobs = dir_.path() / "readonly";
  fs::create_directories(blobs);
  bool mounted = false;
  if (::geteuid() == 0) {
    // Root writes through permission bits: a read-only mount is what stops it.
    mounted = ::mount("tmpfs", blobs.c_str(), "tmpfs", MS_RDONLY, "size=1m") == 0;
    if (!mounted)
      GTEST_SKIP() << "cannot mount a read-only tmpfs here to make an unwritable folder";
  } else {
    fs::permissions(blobs, fs::perms::owner_read | fs::perms::owner_exec);
  }
  StoreLocation location;
  location.database_url = url_;
  location.data_dir = dir_.path() / "data";
  location.blob_dir = blobs;
  const std::string message =
      open_error(OpenError::Kind::kBlobDirUnwritable, [&] { open_store(location); });
  EXPECT_NE(message.find(blobs.string()), std::string::npos) << message;
  if (mounted) ::umount(blobs.c_str());
}

// A private server this test may stop and start: the LISTEN connection comes back, says
// "re-read" (a change without a job id per project), and changes are heard again; the
// store's pool reconnects too.
TEST(PgRestart, ListenerAndPoolReconnectAfterTheServerRestarts) {
  if (PgTestServer::find_binaries().empty()) GTEST_SKIP() << "PostgreSQL is not installed";
  PgTestServer server(PgTestServer::Options{});
  const std::string url = server.create_database();
  testing::TempDir dir;
  PgStoreOptions options;
  options.database_url = url;
  options.blob_dir = dir.path();
  std::unique_ptr<Store> a = std::make_unique<PgStore>(options, system_clock_ms);
  std::unique_ptr<Store> b = std::make_unique<PgStore>(options, system_clock_ms);
  Heard on_b(*b);
  proto::MissionRequest mission;
  mission.name = "m";
  mission.bundle_blob = a->put_blob("bundle");
  const std::string mission_id = a->create_mission(mission).id;
  proto::JobRequest request;
  request.mission_id = mission_id;
  request.stages = {"ingest"};

  server.stop();
  EXPECT_THROW(a->get_mission(mission_id), Unavailable) << "while the database is down";
  server.start();
  EXPECT_TRUE(on_b.wait_for([](const Change& c) { return c.job_id.empty(); }, 15000ms))
      << "after reconnecting, the listener tells its subscribers to re-read";
  const proto::Job job = a->create_job(request, "");
  EXPECT_TRUE(on_b.wait_for([&](const Change& c) { return c.job_id == job.id; }))
      << "changes are heard again";
}

}  // namespace
}  // namespace keel::storage
