#include "tests/storage/pg_test_server.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <pwd.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/types.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <mutex>
#include <pqxx/pqxx>
#include <random>
#include <stdexcept>
#include <system_error>

namespace keel::testing {

namespace fs = std::filesystem;

namespace {

constexpr const char* kRootPrefix = "keel-pg-";

std::string shell_quote(const std::string& arg) {
  std::string out = "'";
  for (char c : arg) {
    if (c == '\'')
      out += "'\\''";
    else
      out += c;
  }
  return out + "'";
}

int free_tcp_port(const std::string& address) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = 0;
  ::inet_pton(AF_INET, address.c_str(), &addr.sin_addr);
  if (::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) != 0) {
    ::close(fd);
    // In another network namespace the address is not ours: any high port will do.
    std::random_device random;
    return 20000 + static_cast<int>(random() % 20000);
  }
  socklen_t size = sizeof(addr);
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &size);
  ::close(fd);
  return ntohs(addr.sin_port);
}

bool is_root() { return ::geteuid() == 0; }

// Folders of earlier test runs that were killed before they could stop their server.
void remove_stale_servers(const fs::path& bin) {
  std::error_code error;
  for (const auto& entry : fs::directory_iterator(fs::temp_directory_path(), error)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind(kRootPrefix, 0) != 0) continue;
    const long pid = std::atol(name.c_str() + std::string(kRootPrefix).size());
    if (pid <= 0 || ::kill(pid, 0) == 0) continue;
    const fs::path data = entry.path() / "data";
    if (fs::exists(data / "postmaster.pid")) {
      const std::string command = (is_root() ? "runuser -u postgres -- " : "") +
                                  shell_quote((bin / "pg_ctl").string()) + " -D " +
                                  shell_quote(data.string()) + " -m immediate stop >/dev/null 2>&1";
      if (std::system(command.c_str()) != 0) continue;
    }
    fs::remove_all(entry.path(), error);
  }
}

std::mutex g_shared_mutex;
std::unique_ptr<PgTestServer> g_shared;
std::string g_reason;
bool g_tried = false;

}  // namespace

fs::path PgTestServer::find_binaries() {
  if (const char* env = std::getenv("KEEL_PG_BIN"); env && *env)
    return fs::exists(fs::path(env) / "initdb") ? fs::path(env) : fs::path();
  fs::path best;
  int best_version = 0;
  std::error_code error;
  for (const auto& entry : fs::directory_iterator("/usr/lib/postgresql", error)) {
    const int version = std::atoi(entry.path().filename().c_str());
    if (version > best_version && fs::exists(entry.path() / "bin" / "initdb")) {
      best_version = version;
      best = entry.path() / "bin";
    }
  }
  return best;
}

PgTestServer* PgTestServer::shared() {
  std::lock_guard<std::mutex> lock(g_shared_mutex);
  if (!g_tried) {
    g_tried = true;
    if (find_binaries().empty()) {
      g_reason =
          "PostgreSQL is not installed (no /usr/lib/postgresql/N/bin/initdb; deploy/setup.sh "
          "installs it): PostgreSQL tests skipped";
    } else {
      g_shared = std::make_unique<PgTestServer>(Options{});
      std::atexit([] { g_shared.reset(); });
    }
  }
  return g_shared.get();
}

std::string PgTestServer::reason() {
  std::lock_guard<std::mutex> lock(g_shared_mutex);
  return g_reason;
}

PgTestServer::PgTestServer(Options options) : options_(std::move(options)) {
  bin_ = find_binaries();
  if (bin_.empty()) throw std::runtime_error("PostgreSQL binaries not found");
  remove_stale_servers(bin_);
  std::random_device random;
  root_ = fs::temp_directory_path() /
          (kRootPrefix + std::to_string(::getpid()) + "-" + std::to_string(random() % 1000000));
  fs::create_directories(root_);
  if (is_root()) {
    const passwd* postgres = ::getpwnam("postgres");
    if (!postgres) throw std::runtime_error("running as root but there is no user 'postgres'");
    if (::chown(root_.c_str(), postgres->pw_uid, postgres->pw_gid) != 0)
      throw std::system_error(errno, std::generic_category(), "chown " + root_.string());
  }
  data_ = root_ / "data";
  log_ = root_ / "postgres.log";
  port_ = options_.listen_address.empty()
              ? (options_.port > 0 ? options_.port : 5432)
              : (options_.port > 0 ? options_.port : free_tcp_port(options_.listen_address));
  run({(bin_ / "initdb").string(), "-D", data_.string(), "-A", "trust", "-U", "postgres", "-N",
       "-E", "UTF8", "--locale=C"});
  start();
}

PgTestServer::~PgTestServer() {
  if (running_) {
    try {
      run({(bin_ / "pg_ctl").string(), "-D", data_.string(), "-m", "immediate", "stop"});
    } catch (const std::exception&) {
    }
  }
  std::error_code ignored;
  fs::remove_all(root_, ignored);
}

std::string PgTestServer::run(const std::vector<std::string>& args, bool as_postgres) {
  std::string command;
  for (const std::string& part : options_.command_prefix) command += shell_quote(part) + " ";
  if (as_postgres && is_root()) command += "runuser -u postgres -- ";
  for (const std::string& arg : args) command += shell_quote(arg) + " ";
  command += "2>&1";
  FILE* pipe = ::popen(command.c_str(), "r");
  if (!pipe) throw std::runtime_error("cannot run " + command);
  std::string output;
  char buffer[4096];
  size_t got;
  while ((got = std::fread(buffer, 1, sizeof(buffer), pipe)) > 0) output.append(buffer, got);
  const int status = ::pclose(pipe);
  if (status != 0) throw std::runtime_error(command + " failed:\n" + output);
  return output;
}

void PgTestServer::start() {
  std::string server_options = "-p " + std::to_string(port_) + " -k " + root_.string() +
                               " -c listen_addresses='" + options_.listen_address + "'" +
                               " -c max_connections=" + std::to_string(options_.max_connections);
  if (!options_.fsync) server_options += " -c fsync=off -c full_page_writes=off";
  run({(bin_ / "pg_ctl").string(), "-D", data_.string(), "-l", log_.string(), "-w", "-t", "60",
       "-o", server_options, "start"});
  running_ = true;
}

void PgTestServer::stop() {
  run({(bin_ / "pg_ctl").string(), "-D", data_.string(), "-m", "fast", "-w", "stop"});
  running_ = false;
}

std::string PgTestServer::url(const std::string& database) const {
  return "postgresql://postgres@/" + database + "?host=" + root_.string() +
         "&port=" + std::to_string(port_);
}

std::string PgTestServer::tcp_url(const std::string& database) const {
  return "postgresql://postgres@" + options_.listen_address + ":" + std::to_string(port_) + "/" +
         database;
}

void PgTestServer::exec(const std::string& database, const std::string& sql) {
  pqxx::connection connection(url(database));
  pqxx::nontransaction work(connection);
  work.exec(sql);
}

std::string PgTestServer::create_database(const std::string& prefix) {
  const std::string name = prefix + "_" + std::to_string(++databases_);
  // FILE_COPY: a checkpoint instead of WAL-logging the template, ~10x faster here.
  exec("postgres", "CREATE DATABASE " + name + " STRATEGY = FILE_COPY");
  return url(name);
}

}  // namespace keel::testing
