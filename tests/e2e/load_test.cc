// Load: 200 concurrent clients for KEEL_LOAD_SECONDS (60 by default), each on its own
// kept-alive connection, mixing job status polls, log follows, 256 KiB upload chunks and
// ranged blob downloads against one real keel-server. Every answer must be the right one
// (0 errors: statuses, upload offsets, completed blobs' hashes, downloaded bytes against the
// uploaded ones); the server's peak RSS (VmHWM) is printed with the request count and rate.
// Each full upload is completed, as a client does: left open, they kept ~8 GB a minute of
// unfinished uploads on the test machine's disk (measured: 137 MB/s on the 2-core machine),
// which once filled CI's disk, and the server rightly answered 507; completed, they are 26
// deduplicated blobs and the disk use stays flat.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <fstream>
#include <mutex>
#include <random>
#include <thread>

#include "core/sha256.h"
#include "tests/e2e/cluster.h"

namespace keel::e2e {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

int64_t peak_rss_kib(int pid) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::atoll(line.c_str() + 6);
  return -1;
}

int server_pid(const fs::path& data_dir) {
  // keel-server's pid: the process whose command line names this data folder.
  for (const auto& entry : fs::directory_iterator("/proc")) {
    const std::string name = entry.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::string cmdline = read_file(entry.path() / "cmdline");
    std::replace(cmdline.begin(), cmdline.end(), '\0', ' ');
    if (cmdline.find("keel-server") != std::string::npos &&
        cmdline.find(data_dir.string()) != std::string::npos)
      return std::stoi(name);
  }
  return -1;
}

TEST(Load, TwoHundredClientsMixingPollsLogsChunksAndRangesGetNoError) {
  const char* seconds_text = std::getenv("KEEL_LOAD_SECONDS");
  const int seconds = seconds_text ? std::max(1, std::atoi(seconds_text)) : 60;
  constexpr int kClients = 200;
  TempDir root;
  const fs::path mission = root.path() / "mission";
  simulate_mission(mission, 3, "imu,dvl,depth");
  Cluster cluster(root.path(), /*workers=*/0, 0,
                  {"--rate-limit", "0", "--threads", "4", "--max-chunk-bytes", "1048576"});
  const RunResult submitted =
      cluster.keel({"submit", mission.string(), "--stages", "ingest", "-q"});
  ASSERT_EQ(submitted.exit_code, 0) << submitted.output;
  client::ClientConfig config;
  config.url = cluster.url();
  config.token = cluster.token();
  config.timeout_s = 60;
  config.chunk_bytes = 512 << 10;  // under the server's --max-chunk-bytes
  std::string job_id;
  std::string blob;
  std::string blob_bytes;
  {
    client::ApiClient api(config);
    job_id = api.list_jobs().at(0).id;
    std::mt19937_64 rng(9);
    blob_bytes.resize(4 << 20);
    for (auto& c : blob_bytes) c = static_cast<char>(rng());
    const fs::path file = root.path() / "download.bin";
    std::ofstream(file, std::ios::binary) << blob_bytes;
    blob = api.upload_file(file, root.path() / "state");
  }
  const int pid = server_pid(cluster.data_dir());
  ASSERT_GT(pid, 0);

  std::atomic<int64_t> requests{0};
  std::mutex mutex;
  std::vector<std::string> errors;
  auto error = [&](const std::string& what) {
    std::lock_guard<std::mutex> lock(mutex);
    if (errors.size() < 20)
      errors.push_back(what);
    else
      errors.back() = "... and more";
  };
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(seconds);
  std::vector<std::thread> threads;
  for (int c = 0; c < kClients; ++c) {
    threads.emplace_back([&, c] {
      client::ApiClient api(config);
      std::mt19937 rng(c);
      std::string upload_id;
      int64_t offset = 0;
      constexpr int64_t kChunk = 256 << 10, kUpload = 16 * kChunk;
      const std::string chunk(kChunk, static_cast<char>('a' + c % 26));
      std::string whole;
      for (int64_t i = 0; i < kUpload / kChunk; ++i) whole += chunk;
      const std::string whole_sha256 = keel::sha256_bytes(whole);
      while (std::chrono::steady_clock::now() < until) {
        try {
          switch (c % 4) {
            case 0: {  // status poll
              const auto r = api.request("GET", "/v1/jobs/" + job_id);
              if (r.status != 200 || r.body.find(job_id) == std::string::npos)
                error("poll: " + std::to_string(r.status));
              break;
            }
            case 1: {  // log follow
              const auto r = api.request("GET", "/v1/jobs/" + job_id + "/log?from=0");
              if (r.status != 200) error("log: " + std::to_string(r.status));
              break;
            }
            case 2: {  // chunk upload; a full upload is completed, then a new one begun
              if (offset == kUpload) {
                const auto r = api.request("POST", "/v1/uploads/" + upload_id + "/complete",
                                           nlohmann::json{{"sha256", whole_sha256}}.dump());
                if (r.status != 200 || r.body.find(whole_sha256) == std::string::npos)
                  error("complete upload: " + std::to_string(r.status) + " " + r.body);
                upload_id.clear();
                offset = 0;
                break;
              }
              if (upload_id.empty()) {
                const auto r =
                    api.request("POST", "/v1/uploads",
                                nlohmann::json{{"name", "load.bin"}, {"size", kUpload}}.dump());
                if (r.status != 201) {
                  error("create upload: " + std::to_string(r.status) + " " + r.body);
                  break;
                }
                upload_id = nlohmann::json::parse(r.body)["id"];
                offset = 0;
              }
              const std::string range = "bytes " + std::to_string(offset) + "-" +
                                        std::to_string(offset + kChunk - 1) + "/" +
                                        std::to_string(kUpload);
              const auto r =
                  api.request("PUT", "/v1/uploads/" + upload_id, chunk, {{"Content-Range", range}});
              if (r.status != 200 || r.headers.count("upload-offset") == 0 ||
                  r.headers.at("upload-offset") != std::to_string(offset + kChunk))
                error("chunk: " + std::to_string(r.status) + " " + r.body);
              else
                offset += kChunk;
              break;
            }
            default: {  // ranged download, checked against the bytes
              const int64_t first =
                  std::uniform_int_distribution<int64_t>(0, (4 << 20) - 70000)(rng);
              const int64_t length = std::uniform_int_distribution<int64_t>(1, 65536)(rng);
              const auto r = api.request("GET", "/v1/blobs/" + blob, "",
                                         {{"Range", "bytes=" + std::to_string(first) + "-" +
                                                        std::to_string(first + length - 1)}});
              if (r.status != 206 || r.body != blob_bytes.substr(first, length))
                error("range: " + std::to_string(r.status));
              break;
            }
          }
        } catch (const std::exception& e) {
          error(std::string("transport: ") + e.what());
        }
        ++requests;
      }
    });
  }
  int64_t rss_peak = 0;
  while (std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(500ms);
    rss_peak = std::max(rss_peak, peak_rss_kib(pid));
  }
  for (auto& thread : threads) thread.join();
  rss_peak = std::max(rss_peak, peak_rss_kib(pid));
  EXPECT_TRUE(errors.empty()) << errors.size() << " errors, first: " << errors.front();
  EXPECT_EQ(client::ApiClient(config).request("GET", "/healthz").status, 200);
  std::cout << kClients << " clients for " << seconds << " s: " << requests << " requests ("
            << requests / seconds << "/s), " << errors.size() << " errors, server peak RSS "
            << rss_peak / 1024 << " MiB\n";
}

}  // namespace
}  // namespace keel::e2e
