// A full disk, for real: keel-server's data folder on an 8 MiB tmpfs mounted by the test
// (in a mount namespace of its own, so nothing leaks to the machine; as non-root in a user
// namespace too). Uploads until the free-space reserve is reached get 507, then with no
// reserve a filled disk makes the database itself refuse (SQLITE_FULL -> 507); the server
// keeps serving reads; nothing is corrupt (PRAGMA integrity_check, every blob's SHA-256 is
// its name, no temp file left); once space is freed the cut upload resumes and completes.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sched.h>
#include <sys/mount.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <map>
#include <random>

#include "core/sha256.h"
#include "storage/sqlite_db.h"
#include "tests/e2e/cluster.h"

namespace keel::e2e {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

constexpr int64_t kFsBytes = 8 << 20;
constexpr int64_t kUploadBytes = 512 << 10;
constexpr int64_t kChunkBytes = 128 << 10;
constexpr int64_t kReserveBytes = 1 << 20;

bool write_text(const std::string& file, const std::string& text) {
  std::ofstream out(file);
  out << text;
  return static_cast<bool>(out.flush());
}

// Enters a private mount namespace (a user namespace first when not root). Must run while
// the process has one thread. "" on success, else why not.
std::string enter_mount_namespace() {
  static std::string result = [] {
    const uid_t uid = ::geteuid();
    const gid_t gid = ::getegid();
    if (uid != 0) {
      if (::unshare(CLONE_NEWUSER | CLONE_NEWNS) != 0)
        return std::string("unshare(CLONE_NEWUSER|CLONE_NEWNS): ") + std::strerror(errno);
      write_text("/proc/self/setgroups", "deny");
      if (!write_text("/proc/self/uid_map", "0 " + std::to_string(uid) + " 1") ||
          !write_text("/proc/self/gid_map", "0 " + std::to_string(gid) + " 1"))
        return std::string("cannot write the user namespace's id maps");
    } else if (::unshare(CLONE_NEWNS) != 0) {
      return std::string("unshare(CLONE_NEWNS): ") + std::strerror(errno);
    }
    if (::mount(nullptr, "/", nullptr, MS_REC | MS_PRIVATE, nullptr) != 0)
      return std::string("mount --make-rprivate /: ") + std::strerror(errno);
    return std::string();
  }();
  return result;
}

int64_t free_bytes(const fs::path& folder) {
  struct statvfs info {};
  if (::statvfs(folder.c_str(), &info) != 0) return -1;
  return static_cast<int64_t>(info.f_bavail) * static_cast<int64_t>(info.f_frsize);
}

std::string random_bytes(std::mt19937_64& rng, int64_t size) {
  std::string out(static_cast<size_t>(size), '\0');
  for (auto& c : out) c = static_cast<char>(rng());
  return out;
}

std::string error_code_of(const client::HttpResult& r) {
  try {
    return nlohmann::json::parse(r.body)["error"]["code"];
  } catch (...) {
    return "";
  }
}

// Writes zeros to `file` until the disk refuses; returns the bytes written.
int64_t fill_disk(const fs::path& file) {
  const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return -1;
  const std::string block(4096, '\0');
  int64_t written = 0;
  for (;;) {
    const ssize_t n = ::write(fd, block.data(), block.size());
    if (n <= 0) break;
    written += n;
  }
  ::close(fd);
  return written;
}

client::HttpResult put_chunk(client::ApiClient& api, const std::string& id,
                             const std::string& bytes, int64_t first, int64_t size) {
  const std::string range = "bytes " + std::to_string(first) + "-" +
                            std::to_string(first + size - 1) + "/" + std::to_string(bytes.size());
  return api.request("PUT", "/v1/uploads/" + id, bytes.substr(first, size),
                     {{"Content-Range", range}});
}

class DiskFull : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string why = enter_mount_namespace();
    if (!why.empty()) GTEST_SKIP() << "cannot make a private mount namespace here: " << why;
    fs::create_directories(data_);
    if (::mount("keel-test", data_.c_str(), "tmpfs", 0,
                ("size=" + std::to_string(kFsBytes)).c_str()) != 0)
      GTEST_SKIP() << "cannot mount a tmpfs on " << data_ << ": " << std::strerror(errno);
    mounted_ = true;
  }
  void TearDown() override {
    cluster_.reset();
    if (mounted_) ::umount2(data_.c_str(), MNT_DETACH);
  }

  void start(int64_t reserve_bytes, int workers = 0) {
    stop();
    cluster_ = std::make_unique<Cluster>(
        root_.path(), workers, 0,
        std::vector<std::string>{"--min-free-bytes", std::to_string(reserve_bytes)});
    client::ClientConfig config;
    config.url = cluster_->url();
    config.token = cluster_->token();
    config.timeout_s = 30;
    api_ = std::make_unique<client::ApiClient>(config);
    running_ = true;
  }

  void stop() {
    if (cluster_ && running_) cluster_->stop_server();
    running_ = false;
  }

  // Nothing corrupt: the database passes integrity_check, every blob's content hashes to its
  // name, and no temporary file is left in tmp/.
  void expect_nothing_corrupt() {
    storage::DatabaseOptions read_only;
    read_only.query_only = true;
    storage::Database db(data_ / "keel.db", read_only);
    auto check = db.cached("PRAGMA integrity_check");
    ASSERT_TRUE(check->step());
    EXPECT_EQ(check->column_text(0), "ok");
    int blobs = 0;
    for (const auto& entry : fs::recursive_directory_iterator(data_ / "blobs")) {
      if (!entry.is_regular_file()) continue;
      ++blobs;
      EXPECT_EQ(keel::sha256_file(entry.path()), entry.path().filename().string())
          << entry.path();
    }
    EXPECT_EQ(blobs, static_cast<int>(blobs_.size()));
    if (fs::exists(data_ / "tmp"))
      EXPECT_TRUE(fs::is_empty(data_ / "tmp")) << "a temporary blob file was left";
  }

  void expect_reads_served() {
    EXPECT_EQ(api_->request("GET", "/healthz").status, 200);
    EXPECT_EQ(api_->request("GET", "/v1/jobs").status, 200);
    for (const auto& [sha256, bytes] : blobs_) {
      const client::HttpResult blob = api_->request("GET", "/v1/blobs/" + sha256);
      EXPECT_EQ(blob.status, 200);
      EXPECT_TRUE(blob.body == bytes) << "blob " << sha256 << " read back different bytes";
    }
  }

  TempDir root_;
  fs::path data_ = root_.path() / "data";
  bool mounted_ = false;
  bool running_ = false;
  std::unique_ptr<Cluster> cluster_;
  std::unique_ptr<client::ApiClient> api_;
  std::map<std::string, std::string> blobs_;  // sha256 -> bytes, completed uploads
};

TEST_F(DiskFull, UploadsAreRefusedWith507BeforeTheDiskIsFullNothingIsCorruptAndTheyResume) {
  start(kReserveBytes);
  std::mt19937_64 rng(15);

  // Announce more uploads than the disk holds (an announcement takes no space), then send
  // their chunks in turn until one is refused.
  struct Open {
    std::string id;
    std::string bytes;
    int64_t offset = 0;
  };
  std::vector<Open> uploads;
  for (int i = 0; i < 16; ++i) {
    Open u;
    u.bytes = random_bytes(rng, kUploadBytes);
    const client::HttpResult made = api_->request(
        "POST", "/v1/uploads",
        nlohmann::json{{"name", "part" + std::to_string(i) + ".bin"}, {"size", kUploadBytes}}
            .dump());
    ASSERT_EQ(made.status, 201) << made.body;
    u.id = nlohmann::json::parse(made.body)["id"];
    uploads.push_back(std::move(u));
  }
  Open* cut = nullptr;
  for (Open& u : uploads) {
    while (u.offset < kUploadBytes && !cut) {
      const client::HttpResult r = put_chunk(*api_, u.id, u.bytes, u.offset, kChunkBytes);
      if (r.status == 200) {
        u.offset += kChunkBytes;
        continue;
      }
      EXPECT_EQ(r.status, 507) << r.body;
      EXPECT_EQ(error_code_of(r), "insufficient_storage") << r.body;
      EXPECT_NE(r.body.find("in reserve"), std::string::npos) << r.body;
      // Refused before the disk was full: the reserve is still (nearly all) there.
      const int64_t free = free_bytes(data_);
      EXPECT_GT(free, kReserveBytes - kChunkBytes) << "free bytes when refused";
      cut = &u;
    }
    if (cut) break;
    const std::string sha256 = keel::sha256_bytes(u.bytes);
    const client::HttpResult done = api_->request("POST", "/v1/uploads/" + u.id + "/complete",
                                                  nlohmann::json{{"sha256", sha256}}.dump());
    ASSERT_EQ(done.status, 200) << done.body;
    blobs_[sha256] = u.bytes;
  }
  ASSERT_TRUE(cut) << "8 MiB of uploads fitted on an 8 MiB disk with a reserve";
  ASSERT_GE(blobs_.size(), 4u);
  // A new upload that would eat into the reserve is refused at once, naming it.
  const client::HttpResult big = api_->request(
      "POST", "/v1/uploads", nlohmann::json{{"name", "big.bin"}, {"size", kFsBytes}}.dump());
  EXPECT_EQ(big.status, 507) << big.body;
  EXPECT_NE(big.body.find("upload 'big.bin'"), std::string::npos) << big.body;
  expect_reads_served();

  // No reserve, and the disk filled to the last byte by someone else: the database cannot
  // grow, so writes are refused with 507 (SQLITE_FULL), never 500, and reads go on.
  start(0);
  const int64_t filler = fill_disk(data_ / "filler");
  ASSERT_GT(filler, 0);
  EXPECT_LT(free_bytes(data_), 4096);
  int refused = 0, accepted = 0;
  std::string database_full;
  for (int i = 0; i < 4000 && refused < 5; ++i) {
    const client::HttpResult r = api_->request(
        "POST", "/v1/uploads", nlohmann::json{{"name", "empty.bin"}, {"size", 0}}.dump());
    if (r.status == 201) {
      ++accepted;
      continue;
    }
    ASSERT_EQ(r.status, 507) << "after " << accepted << " accepted: " << r.body;
    EXPECT_EQ(error_code_of(r), "insufficient_storage");
    if (r.body.find("database") != std::string::npos) database_full = r.body;
    ++refused;
  }
  EXPECT_GT(refused, 0) << accepted << " uploads made on a full disk";
  const client::HttpResult chunk = put_chunk(*api_, cut->id, cut->bytes, cut->offset, kChunkBytes);
  EXPECT_EQ(chunk.status, 507) << chunk.body;
  expect_reads_served();
  const client::HttpResult head = api_->request("HEAD", "/v1/uploads/" + cut->id);
  EXPECT_EQ(head.status, 200);
  EXPECT_EQ(head.headers.at("upload-offset"), std::to_string(cut->offset));
  stop();
  expect_nothing_corrupt();
  std::cout << "refused " << refused << " writes on the full disk after " << accepted
            << " fitted; database refusal: " << database_full << "\n";

  // Space freed: the cut upload resumes where it stopped and completes with its bytes.
  fs::remove(data_ / "filler");
  start(kReserveBytes);
  const client::HttpResult offset = api_->request("HEAD", "/v1/uploads/" + cut->id);
  ASSERT_EQ(offset.status, 200);
  int64_t at = std::stoll(offset.headers.at("upload-offset"));
  EXPECT_EQ(at, cut->offset);
  for (; at < kUploadBytes; at += kChunkBytes) {
    const client::HttpResult r = put_chunk(*api_, cut->id, cut->bytes, at, kChunkBytes);
    ASSERT_EQ(r.status, 200) << r.body;
  }
  const std::string sha256 = keel::sha256_bytes(cut->bytes);
  const client::HttpResult done = api_->request("POST", "/v1/uploads/" + cut->id + "/complete",
                                                nlohmann::json{{"sha256", sha256}}.dump());
  ASSERT_EQ(done.status, 200) << done.body;
  blobs_[sha256] = cut->bytes;
  expect_reads_served();
  stop();
  expect_nothing_corrupt();
}

// A job whose products the server cannot store fails, saying so in the server's words: the
// worker's upload of its artifacts is answered 507, which is no reason to abandon the lease
// (the job would then fail as "lease expired 3 times", naming nothing: CI saw it once, when
// another test had filled the machine's disk).
TEST_F(DiskFull, AJobWhoseProductsCannotBeStoredFailsNamingTheServersDisk) {
  const fs::path mission = root_.path() / "mission";  // not on the small disk
  simulate_mission(mission, 3, "imu,dvl,depth");
  start(kReserveBytes);
  const RunResult submitted =
      cluster_->keel({"submit", mission.string(), "--stages", "ingest", "-q"});
  ASSERT_EQ(submitted.exit_code, 0) << submitted.output;
  const std::string job = api_->list_jobs().at(0).id;
  // The whole disk kept in reserve: the worker gets the mission, runs, and cannot upload.
  start(kFsBytes, /*workers=*/1);
  const proto::Job done = wait_job(
      *api_, job, [](const proto::Job& j) { return proto::is_terminal(j.state); }, 120);
  ASSERT_EQ(done.state, proto::JobState::kFailed) << proto::to_string(done.state);
  EXPECT_NE(done.error.find("the server's disk has"), std::string::npos) << done.error;
  EXPECT_NE(done.error.find("in reserve"), std::string::npos) << done.error;
  EXPECT_EQ(done.attempts, 1) << done.error;
}

}  // namespace
}  // namespace keel::e2e
