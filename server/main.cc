// keel-server: Keel's HTTP API, its store in --data-dir and N local workers.
//
//   keel-server --data-dir DIR [--listen 127.0.0.1:8080] [--workers N] [--worker-binary P]
//               [--max-chunk-bytes B] [--threads T] [--web-dir D] [--tls-cert F --tls-key F]
//               [--max-connections N] [--min-free-bytes B] [--rate-limit R --rate-burst B]
//               [--database postgresql://... --blob-dir SHARED] [--requeue-seconds S]
//   keel-server --data-dir DIR [--database ...] token create --project P --role R
//               [--expires 30d] [--label L]
//   keel-server --data-dir DIR [--database ...] token list
//   keel-server --data-dir DIR [--database ...] token revoke TOKEN_ID
//
// The store is SQLite in --data-dir unless --database (or $KEEL_DATABASE_URL) names a
// PostgreSQL database; then several replicas share it and the blob folder --blob-dir.
// A store that cannot be opened ends the program before it listens, with an exit code
// saying why (kExit* below, docs/deploy.md).
//
// Prints the URL it listens on (also written to <data-dir>/server.url) once it accepts
// connections. SIGTERM/SIGINT: workers are stopped first (they may still report to the
// server while they wind down), then the server stops accepting, lets requests in flight
// finish, and exits 0. The token commands open the same store and may run while the server
// does; `token create` prints the new token (only that) on stdout.
#include <signal.h>
#include <spdlog/spdlog.h>
#include <sys/resource.h>
#include <unistd.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <iostream>

#include "server/data_dir.h"
#include "server/http_handler.h"
#include "server/http_server.h"
#include "server/requeue_loop.h"
#include "server/static_files.h"
#include "server/token_admin.h"
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
  std::string tls_cert;
  std::string tls_key;
  int max_connections = 4096;
  int64_t min_free_bytes = int64_t{256} << 20;
  double rate_limit = 200.0;  // requests per second per token
  double rate_burst = 400.0;
};

// Each connection holds a descriptor: let the soft limit reach what max_connections needs
// (plus files, the database and workers' logs), up to the hard limit.
void raise_open_file_limit(int max_connections) {
  struct rlimit limit {};
  if (getrlimit(RLIMIT_NOFILE, &limit) != 0) return;
  const rlim_t wanted = static_cast<rlim_t>(max_connections) + 256;
  if (limit.rlim_cur >= wanted) return;
  limit.rlim_cur = limit.rlim_max == RLIM_INFINITY ? wanted : std::min(wanted, limit.rlim_max);
  if (setrlimit(RLIMIT_NOFILE, &limit) != 0)
    spdlog::warn("cannot raise the open file limit to {}: {}", wanted, std::strerror(errno));
}

// The store the server uses (the token commands open the same one).
std::unique_ptr<keel::storage::Store> open_settings_store(const Settings& settings) {
  keel::storage::StoreLocation location;
  location.database_url = settings.database;
  location.data_dir = settings.data_dir;
  location.blob_dir = settings.blob_dir;
  return keel::storage::open_store(location);
}

struct TokenArgs {
  std::string project;
  std::string role;
  std::string expires = "never";
  std::string label;
  std::string token_id;
};

std::string format_time_ms(int64_t ms) {
  if (ms == 0) return "-";
  const std::time_t seconds = static_cast<std::time_t>(ms / 1000);
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char text[32];
  std::strftime(text, sizeof(text), "%Y-%m-%dT%H:%M:%SZ", &utc);
  return text;
}

int token_create(const Settings& settings, const TokenArgs& args) {
  keel::proto::TokenRequest request;
  try {
    request = keel::proto::TokenRequest::from_json(
        {{"label", args.label},
         {"role", args.role},
         {"project", args.project},
         {"expires_in_s", keel::server::parse_duration_seconds(args.expires)}},
        "");
  } catch (const std::exception& e) {
    std::cerr << "keel-server token create: " << e.what() << "\n";
    return 2;
  }
  auto store = open_settings_store(settings);
  const auto issued = keel::server::issue_token(*store, request, keel::storage::system_clock_ms());
  std::cerr << "made " << issued.info.id << ": role " << keel::proto::to_string(issued.info.role)
            << ", project " << issued.info.project << ", expires "
            << format_time_ms(issued.info.expires_at_ms) << "\n";
  std::cout << issued.token << std::endl;
  return 0;
}

int token_list(const Settings& settings) {
  auto store = open_settings_store(settings);
  const int64_t now = keel::storage::system_clock_ms();
  std::printf("%-20s %-9s %-20s %-8s %-20s %-20s %s\n", "ID", "ROLE", "PROJECT", "STATE", "CREATED",
              "EXPIRES", "LABEL");
  for (const auto& token : store->list_tokens()) {
    const char* state = token.revoked_at_ms                                 ? "revoked"
                        : token.expires_at_ms && token.expires_at_ms <= now ? "expired"
                                                                            : "active";
    std::printf("%-20s %-9s %-20s %-8s %-20s %-20s %s\n", token.id.c_str(),
                keel::proto::to_string(token.role).c_str(), token.project.c_str(), state,
                format_time_ms(token.created_at_ms).c_str(),
                format_time_ms(token.expires_at_ms).c_str(), token.label.c_str());
  }
  return 0;
}

int token_revoke(const Settings& settings, const TokenArgs& args) {
  auto store = open_settings_store(settings);
  try {
    const auto token = store->revoke_token(args.token_id);
    std::cout << "revoked " << token.id << " (" << keel::proto::to_string(token.role) << ", "
              << token.project << ")" << std::endl;
    return 0;
  } catch (const keel::storage::NotFound& e) {
    std::cerr << "keel-server token revoke: " << e.what() << "\n";
    return 2;
  }
}

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
  auto store = open_settings_store(settings);
  keel::server::RequeueLoop requeue(
      *store, std::chrono::milliseconds(static_cast<int64_t>(settings.requeue_seconds * 1000)));
  if (const int stale = ks::remove_stale_temp_files(settings.data_dir))
    spdlog::info("removed {} temporary files a crash left in {}", stale,
                 settings.data_dir.string());
  if (ks::ensure_initial_token(*store, settings.data_dir))
    spdlog::info("made a first API token in {}", (settings.data_dir / "token").string());
  // Local workers get a worker token, not the admin token.
  const std::filesystem::path worker_token =
      settings.workers > 0 ? ks::ensure_worker_token(*store, settings.data_dir)
                           : std::filesystem::path();

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
  handler_options.min_free_bytes = settings.min_free_bytes;
  handler_options.rate_limit.rate_per_s = settings.rate_limit;
  handler_options.rate_limit.burst = settings.rate_burst;
  handler_options.free_bytes = [dir = settings.data_dir] { return ks::free_bytes_at(dir); };
  ks::HttpHandler handler(*store, handler_options);

  ks::ServerOptions server_options;
  server_options.address = listen.host;
  server_options.port = listen.port;
  server_options.threads = settings.threads;
  server_options.read_timeout =
      std::chrono::milliseconds(static_cast<int64_t>(settings.read_timeout_s * 1000));
  server_options.max_connections = settings.max_connections;
  raise_open_file_limit(settings.max_connections);
  ks::ServerOptions loopback_options = server_options;  // before the TLS files are set
  server_options.tls_cert_file = settings.tls_cert;
  server_options.tls_key_file = settings.tls_key;
  ks::HttpServer server(handler, server_options);
  server.start();
  const std::string url = server.url();
  ks::write_file_atomically(settings.data_dir / "server.url", url);

  // Workers reach the server on loopback whatever address it listens on. With TLS they get
  // a plain-HTTP listener of their own on 127.0.0.1 (an ephemeral port nothing else is told
  // of): the certificate names the public host, and loopback traffic needs no encryption.
  std::unique_ptr<ks::HttpServer> loopback;
  if (!settings.tls_cert.empty() && settings.workers > 0) {
    loopback_options.address = "127.0.0.1";
    loopback_options.port = 0;
    loopback = std::make_unique<ks::HttpServer>(handler, loopback_options);
    loopback->start();
  }
  const std::string worker_url =
      loopback ? loopback->url()
      : listen.host == "0.0.0.0" || listen.host == "127.0.0.1" || listen.host == "localhost"
          ? "http://127.0.0.1:" + std::to_string(server.port())
          : url;
  supervisor.start({"--server", worker_url, "--token-file", worker_token.string(),
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
  if (loopback) loopback->stop();
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
  app.add_option("--tls-cert", settings.tls_cert,
                 "serve HTTPS (TLS 1.2+) with this PEM certificate chain (needs --tls-key)");
  app.add_option("--tls-key", settings.tls_key, "the PEM private key of --tls-cert");
  app.add_option("--max-connections", settings.max_connections,
                 "open connections at most; more wait in the listen queue (0 = no limit)")
      ->check(CLI::Range(0, 1 << 20))
      ->capture_default_str();
  app.add_option(
         "--min-free-bytes", settings.min_free_bytes,
         "free space kept on the data folder's disk: uploads that would go below it get 507")
      ->check(CLI::Range(int64_t{0}, int64_t{1} << 50))
      ->capture_default_str();
  app.add_option("--rate-limit", settings.rate_limit,
                 "requests per second per API token; more get 429 with Retry-After (0 = none)")
      ->check(CLI::Range(0.0, 1e9))
      ->capture_default_str();
  app.add_option("--rate-burst", settings.rate_burst, "requests a token may make at once")
      ->check(CLI::Range(1.0, 1e9))
      ->capture_default_str();
  app.add_option("--log-level", settings.log_level, "trace, debug, info, warn, error")
      ->capture_default_str();

  TokenArgs token_args;
  CLI::App* token = app.add_subcommand("token", "make, list and revoke API tokens");
  token->require_subcommand(1);
  token->fallthrough();
  CLI::App* create = token->add_subcommand("create", "make a token and print it on stdout");
  create->fallthrough();
  create->add_option("--project", token_args.project, "its project, or '*' (admin, worker)")
      ->required();
  create->add_option("--role", token_args.role, "admin, submitter, viewer or worker")->required();
  create->add_option("--expires", token_args.expires, "lifetime: 90s, 45m, 12h, 30d, 2w or never")
      ->capture_default_str();
  create->add_option("--label", token_args.label, "a note saying whose token it is");
  CLI::App* list = token->add_subcommand("list", "every token (revoked and expired ones too)");
  list->fallthrough();
  CLI::App* revoke = token->add_subcommand("revoke", "revoke a token by its id (t_...)");
  revoke->fallthrough();
  revoke->add_option("id", token_args.token_id, "the token's id, from `token list`")->required();
  CLI11_PARSE(app, argc, argv);

  spdlog::set_level(spdlog::level::from_str(settings.log_level));
  try {
    if (*create) return token_create(settings, token_args);
    if (*list) return token_list(settings);
    if (*revoke) return token_revoke(settings, token_args);
    return run(settings);
  } catch (const keel::storage::OpenError& e) {
    spdlog::critical("keel-server: {}", e.what());
    return exit_code_of(e.kind);
  } catch (const std::exception& e) {
    spdlog::critical("keel-server: {}", e.what());
    return 1;
  }
}
