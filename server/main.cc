// keel-server: Keel's HTTP API, its store in --data-dir and N local workers.
//
//   keel-server --data-dir DIR [--listen 127.0.0.1:8080] [--workers N] [--worker-binary P]
//               [--max-chunk-bytes B] [--threads T] [--web-dir D]
//               [--database postgresql://... --blob-dir SHARED] [--requeue-seconds S]
//
// The store is SQLite in --data-dir unless --database (or $KEEL_DATABASE_URL) names a
// PostgreSQL database; then several replicas share it and the blob folder --blob-dir.
// A store that cannot be opened ends the program before it listens, with an exit code
// saying why (kExit* below, docs/deploy.md).
//
// Prints the URL it listens on (also written to <data-dir>/server.url) once it accepts
// connections. SIGTERM/SIGINT: workers are stopped first (they may still report to the
// server while they wind down), then the server stops accepting, lets requests in flight
// finish, and exits 0.
#include <signal.h>
#include <spdlog/spdlog.h>
#include <unistd.h>
#include <CLI/CLI.hpp>

#include <cstdio>
#include <filesystem>
#include <iostream>

#include "server/data_dir.h"
#include "server/http_handler.h"
#include "server/http_server.h"
#include "server/requeue_loop.h"
#include "server/static_files.h"
#include "server/worker_supervisor.h"
#include "storage/open_store.h"
#include "storage/store.h"

namespace {

std::filesystem::path default_worker_binary() {
  std::error_code ec;
  std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) return "keel-worker";
  return self.parent_path() / "keel-worker";
}

// The dashboard's files, installed by the build next to the binaries: <prefix>/share/keel/web.
std::filesystem::path default_web_dir() {
  std::error_code ec;
  std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) return "share/keel/web";
  return self.parent_path().parent_path() / "share" / "keel" / "web";
}

// Exit codes for a store that cannot be opened (1 = any other error at start).
constexpr int kExitBadDatabaseUrl = 3;
constexpr int kExitDatabaseUnreachable = 4;
constexpr int kExitSchemaTooNew = 5;
constexpr int kExitFolderNotWritable = 6;

int exit_code_of(keel::storage::OpenError::Kind kind) {
  using Kind = keel::storage::OpenError::Kind;
  switch (kind) {
    case Kind::kBadUrl:
      return kExitBadDatabaseUrl;
    case Kind::kUnreachable:
      return kExitDatabaseUnreachable;
    case Kind::kSchemaTooNew:
      return kExitSchemaTooNew;
    case Kind::kBlobDirUnwritable:
      return kExitFolderNotWritable;
  }
  return 1;
}

struct Settings {
  std::filesystem::path data_dir;
  std::string database;  // "" = SQLite in data_dir
  std::filesystem::path blob_dir;
  double requeue_seconds = 5.0;
  std::string listen = "127.0.0.1:8080";
  int workers = 1;
  std::string worker_binary;
  std::string web_dir;
  int worker_lease_seconds = 30;
  uint64_t max_chunk_bytes = 64ull << 20;
  int threads = 2;
  double read_timeout_s = 30.0;
  std::string log_level = "info";
};

int run(const Settings& settings) {
  namespace ks = keel::server;
  // Block the stop signals in every thread (threads inherit the mask); main waits for them.
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGTERM);
  sigaddset(&stop_signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);
  signal(SIGPIPE, SIG_IGN);

  const ks::ListenAddress listen = ks::parse_listen_address(settings.listen);
  keel::storage::StoreLocation location;
  location.database_url = settings.database;
  location.data_dir = settings.data_dir;
  location.blob_dir = settings.blob_dir;
  auto store = keel::storage::open_store(location);
  keel::server::RequeueLoop requeue(
      *store, std::chrono::milliseconds(static_cast<int64_t>(settings.requeue_seconds * 1000)));
  if (ks::ensure_initial_token(*store, settings.data_dir))
    spdlog::info("made a first API token in {}", (settings.data_dir / "token").string());

  ks::SupervisorOptions supervisor_options;
  supervisor_options.workers = settings.workers;
  supervisor_options.worker_binary = settings.worker_binary.empty()
                                         ? default_worker_binary()
                                         : std::filesystem::path(settings.worker_binary);
  supervisor_options.log_dir = settings.data_dir / "logs";
  ks::WorkerSupervisor supervisor(supervisor_options);

  ks::HandlerOptions handler_options;
  handler_options.max_chunk_bytes = settings.max_chunk_bytes;
  handler_options.workers_alive = [&supervisor] { return supervisor.alive(); };
  const std::filesystem::path web_dir =
      settings.web_dir.empty() ? default_web_dir() : std::filesystem::path(settings.web_dir);
  handler_options.web = std::make_shared<ks::StaticFiles>(web_dir);
  if (!std::filesystem::exists(web_dir / "index.html"))
    spdlog::warn("no web dashboard in {} (no index.html): / answers 404", web_dir.string());
  ks::HttpHandler handler(*store, handler_options);

  ks::ServerOptions server_options;
  server_options.address = listen.host;
  server_options.port = listen.port;
  server_options.threads = settings.threads;
  server_options.read_timeout =
      std::chrono::milliseconds(static_cast<int64_t>(settings.read_timeout_s * 1000));
  ks::HttpServer server(handler, server_options);
  server.start();
  const std::string url = server.url();
  ks::write_file_atomically(settings.data_dir / "server.url", url);

  // Workers reach the server on loopback whatever address it listens on.
  const std::string worker_url =
      listen.host == "0.0.0.0" || listen.host == "127.0.0.1" || listen.host == "localhost"
          ? "http://127.0.0.1:" + std::to_string(server.port())
          : url;
  supervisor.start({"--server", worker_url, "--token-file", (settings.data_dir / "token").string(),
                    "--lease-seconds", std::to_string(settings.worker_lease_seconds),
                    "--exit-with-parent", std::to_string(::getpid())});

  std::cout << url << std::endl;
  spdlog::info(
      "keel-server listening on {} with {} io threads, {} workers, data in {}, store {}", url,
      settings.threads, settings.workers, settings.data_dir.string(),
      settings.database.empty() ? "SQLite" : keel::storage::redact_database_url(settings.database));

  int received = 0;
  sigwait(&stop_signals, &received);
  spdlog::info("signal {}: stopping workers, then the server", received);
  supervisor.stop();
  server.stop();
  spdlog::info("stopped");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"keel-server: Keel's HTTP API, job queue and artifact store"};
  Settings settings;
  app.add_option("--data-dir", settings.data_dir, "folder for keel.db, blobs, uploads, token, logs")
      ->required();
  app.add_option("--database", settings.database,
                 "postgresql://user@host:port/db for several replicas on one PostgreSQL "
                 "(default: SQLite in --data-dir)")
      ->envname("KEEL_DATABASE_URL");
  app.add_option("--blob-dir", settings.blob_dir,
                 "with --database: the blob folder every replica shares (NFS, a ReadWriteMany "
                 "volume; default --data-dir)");
  app.add_option("--requeue-seconds", settings.requeue_seconds,
                 "how often expired leases are requeued")
      ->check(CLI::Range(0.1, 3600.0))
      ->capture_default_str();
  app.add_option("--listen", settings.listen, "address:port to listen on (port 0 = any free port)")
      ->capture_default_str();
  app.add_option("--workers", settings.workers, "local keel-worker processes to run (0 = none)")
      ->check(CLI::Range(0, 256))
      ->capture_default_str();
  app.add_option("--worker-binary", settings.worker_binary,
                 "keel-worker executable (default: next to keel-server)");
  app.add_option(
      "--web-dir", settings.web_dir,
      "the web dashboard's files, served at / (default: ../share/keel/web from the binary)");
  app.add_option("--worker-lease-seconds", settings.worker_lease_seconds,
                 "lease the local workers ask for: a crashed worker's job is re-run after it")
      ->check(CLI::Range(1, 3600));
  app.add_option("--max-chunk-bytes", settings.max_chunk_bytes, "largest upload chunk (PUT body)")
      ->check(CLI::Range(uint64_t{1}, uint64_t{1} << 34))
      ->capture_default_str();
  app.add_option("--threads", settings.threads, "io threads")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
  app.add_option("--read-timeout", settings.read_timeout_s,
                 "seconds a read may stall before the connection is dropped")
      ->check(CLI::Range(0.1, 3600.0))
      ->capture_default_str();
  app.add_option("--log-level", settings.log_level, "trace, debug, info, warn, error")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  spdlog::set_level(spdlog::level::from_str(settings.log_level));
  try {
    return run(settings);
  } catch (const keel::storage::OpenError& e) {
    spdlog::critical("keel-server: {}", e.what());
    return exit_code_of(e.kind);
  } catch (const std::exception& e) {
    spdlog::critical("keel-server: {}", e.what());
    return 1;
  }
}
