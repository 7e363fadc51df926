#include "server/data_dir.h"

#include <fcntl.h>
#include <openssl/rand.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <stdexcept>

namespace keel::server {

namespace {

std::runtime_error io_error(const std::string& what, const std::filesystem::path& path) {
  return std::runtime_error(what + " " + path.string() + ": " + std::strerror(errno));
}

}  // namespace

void write_file_atomically(const std::filesystem::path& path, const std::string& content,
                           mode_t mode) {
  const std::filesystem::path temp = path.string() + ".tmp." + std::to_string(getpid());
  int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, mode);
  if (fd < 0) throw io_error("cannot create", temp);
  // The umask may have removed bits; a token file must be exactly 0600 either way.
  if (fchmod(fd, mode) != 0) {
    ::close(fd);
    throw io_error("cannot chmod", temp);
  }
  size_t written = 0;
  while (written < content.size()) {
    ssize_t n = ::write(fd, content.data() + written, content.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      ::close(fd);
      throw io_error("cannot write", temp);
    }
    written += static_cast<size_t>(n);
  }
  if (::fsync(fd) != 0 || ::close(fd) != 0) throw io_error("cannot sync", temp);
  if (std::rename(temp.c_str(), path.c_str()) != 0) throw io_error("cannot rename to", path);
}

std::string random_token() {
  unsigned char bytes[32];
  if (RAND_bytes(bytes, sizeof(bytes)) != 1) throw std::runtime_error("RAND_bytes failed");
  static const char* kHex = "0123456789abcdef";
  std::string out;
  for (unsigned char b : bytes) {
    out.push_back(kHex[b >> 4]);
    out.push_back(kHex[b & 15]);
  }
  return out;
}

bool ensure_initial_token(storage::Store& store, const std::filesystem::path& data_dir) {
  if (store.token_count() > 0) return false;
  const std::string token = random_token();
  // The file first: a crash between the two steps leaves an unused file, not a lost token.
  write_file_atomically(data_dir / "token", token, 0600);
  store.add_token(token, storage::admin_token("initial"));
  return true;
}

std::filesystem::path ensure_worker_token(storage::Store& store,
                                          const std::filesystem::path& data_dir) {
  const std::filesystem::path file = data_dir / "worker-token";
  std::string existing;
  {
    std::ifstream in(file);
    std::getline(in, existing);
  }
  if (!existing.empty()) {
    const auto info = store.check_token(existing);
    if (info && info->role == proto::Role::kWorker && info->all_projects()) return file;
  }
  const std::string token = random_token();
  storage::TokenSpec spec;
  spec.label = "local workers";
  spec.role = proto::Role::kWorker;
  spec.project = proto::kAllProjects;
  // The store first: a worker started between the two steps reads the old (refused) token
  // and retries; the reverse order could leave a file whose token the store never had.
  store.add_token(token, spec);
  write_file_atomically(file, token, 0600);
  return file;
}

int64_t free_bytes_at(const std::filesystem::path& folder) {
  struct statvfs info {};
  if (::statvfs(folder.c_str(), &info) != 0) return -1;
  return static_cast<int64_t>(info.f_bavail) * static_cast<int64_t>(info.f_frsize);
}

int remove_stale_temp_files(const std::filesystem::path& data_dir) {
  int removed = 0;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(data_dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (entry.is_regular_file() && name.find(".tmp.") != std::string::npos) {
      std::filesystem::remove(entry.path(), ec);
      if (!ec) ++removed;
    }
  }
  return removed;
}

ListenAddress parse_listen_address(const std::string& text) {
  ListenAddress out;
  std::string port_text;
  if (!text.empty() && text.front() == '[') {
    size_t close = text.find(']');
    if (close == std::string::npos || close + 1 >= text.size() || text[close + 1] != ':')
      throw std::invalid_argument("--listen '" + text + "': expected [ipv6]:port");
    out.host = text.substr(1, close - 1);
    port_text = text.substr(close + 2);
  } else {
    size_t colon = text.rfind(':');
    if (colon == std::string::npos || colon == 0)
      throw std::invalid_argument("--listen '" + text +
                                  "': expected host:port, e.g. 127.0.0.1:8080");
    out.host = text.substr(0, colon);
    port_text = text.substr(colon + 1);
  }
  if (port_text.empty() || port_text.size() > 5 ||
      port_text.find_first_not_of("0123456789") != std::string::npos ||
      std::stoi(port_text) > 65535)
    throw std::invalid_argument("--listen '" + text + "': port must be 0..65535");
  out.port = static_cast<uint16_t>(std::stoi(port_text));
  return out;
}

}  // namespace keel::server
