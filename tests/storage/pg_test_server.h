// A private PostgreSQL for tests: initdb into a temporary folder (as user postgres through
// runuser when the test runs as root), pg_ctl start on a private socket folder (and a TCP
// address when asked), one fresh database per test, stopped and removed at exit. No system
// service is used. Tests skip, saying why, when the PostgreSQL binaries are absent.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace keel::testing {

class PgTestServer {
 public:
  struct Options {
    std::string listen_address;  // "" = unix socket only; else e.g. "127.0.0.1" or "10.0.0.1"
    int port = 0;                // 0 = a free port (TCP) or 5432 (socket only)
    bool fsync = false;          // tests do not need durability across a power cut
    // Run the server's commands under this prefix (e.g. {"ip", "netns", "exec", "db"}).
    std::vector<std::string> command_prefix;
    int max_connections = 200;
  };

  // The folder of initdb/pg_ctl (the newest /usr/lib/postgresql/N/bin, or $KEEL_PG_BIN), or
  // "" when PostgreSQL is not installed.
  static std::filesystem::path find_binaries();
  // The server shared by one test binary, started on first use; nullptr when PostgreSQL is
  // absent (reason() says why, for GTEST_SKIP).
  static PgTestServer* shared();
  static std::string reason();

  explicit PgTestServer(Options options);  // initdb + start; throws naming what failed
  ~PgTestServer();                         // stop (immediate) and remove the folder
  PgTestServer(const PgTestServer&) = delete;
  PgTestServer& operator=(const PgTestServer&) = delete;

  // A new empty database (CREATE DATABASE) and its URL.
  std::string create_database(const std::string& prefix = "keel_test");
  // URL of `database` through the socket folder, or through TCP when listening on it.
  std::string url(const std::string& database) const;
  std::string tcp_url(const std::string& database) const;
  void exec(const std::string& database, const std::string& sql);

  void stop();   // pg_ctl stop -m fast (connections break)
  void start();  // pg_ctl start again, same data

  int port() const { return port_; }
  const std::filesystem::path& socket_dir() const { return root_; }
  const std::filesystem::path& log_file() const { return log_; }

 private:
  // Runs `args` (under the prefix, as postgres when root); throws with its output on failure.
  std::string run(const std::vector<std::string>& args, bool as_postgres = true);

  Options options_;
  std::filesystem::path bin_;
  std::filesystem::path root_;  // socket folder; data/ below it
  std::filesystem::path data_;
  std::filesystem::path log_;
  int port_ = 5432;
  int databases_ = 0;
  bool running_ = false;
};

}  // namespace keel::testing
