// ApiClient::download: GET with Range resume into `<destination>.part`, streamed to disk
// through a buffer_body parser (never the whole body in memory), SHA-256 check, rename.
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <vector>

#include "client/api_client.h"
#include "client/api_client_connection.h"
#include "client/http_ranges.h"
#include "core/sha256.h"

namespace keel::client {

namespace fs = std::filesystem;

namespace {

constexpr size_t kReadBufferBytes = 1 << 20;
constexpr size_t kMaxErrorBodyBytes = 64 << 10;

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using FilePtr = std::unique_ptr<std::FILE, FileCloser>;

FilePtr open_part(const fs::path& part, bool append) {
  FilePtr file(std::fopen(part.c_str(), append ? "ab" : "wb"));
  if (!file)
    throw std::runtime_error(part.string() + ": cannot open for writing: " + std::strerror(errno));
  return file;
}

int64_t part_size(const fs::path& part) {
  std::error_code ec;
  const auto size = fs::file_size(part, ec);
  return ec ? 0 : static_cast<int64_t>(size);
}

}  // namespace

bool ApiClient::download_once(const std::string& target, const fs::path& part,
                              const ProgressFn& progress) {
  const int64_t offset = part_size(part);
  const std::string what = connection_->describe("GET", connection_->target(target));
  http::request<http::empty_body> req{http::verb::get, connection_->target(target), 11};
  std::map<std::string, std::string> headers;
  if (offset > 0) headers["Range"] = range_from_header(offset);
  connection_->prepare(req, headers);

  connection_->ensure_open(what);
  http::response_parser<http::buffer_body> parser;
  parser.body_limit(kNoBodyLimit);
  boost::beast::error_code ec = connection_->write(req);
  if (!ec) ec = connection_->read_header(parser);
  if (ec) {
    connection_->close();
    throw ApiCallError(0, "transport", what + ": " + ec.message());
  }
  const int status = static_cast<int>(parser.get().result_int());
  const std::string content_range(parser.get()[http::field::content_range]);

  std::vector<char> buffer(kReadBufferBytes);
  // Reads the body piece by piece; `sink` gets each piece. Closes the link on any error.
  auto read_body = [&](auto&& sink) {
    while (!parser.is_done()) {
      parser.get().body().data = buffer.data();
      parser.get().body().size = buffer.size();
      ec = connection_->read(parser);
      if (ec == http::error::need_buffer) ec = {};
      // Bytes that arrived before a cut are kept: the next attempt resumes after them.
      sink(buffer.data(), buffer.size() - parser.get().body().size);
      if (ec) {
        connection_->close();
        throw ApiCallError(0, "transport", what + ": " + ec.message());
      }
    }
    if (!parser.get().keep_alive()) connection_->close();
  };

  if (status != 200 && status != 206) {
    HttpResult error;
    error.status = status;
    read_body([&](const char* data, size_t n) {
      if (error.body.size() < kMaxErrorBodyBytes) error.body.append(data, n);
    });
    if (status == 416 && offset > 0) {
      // The part already holds every byte (total == offset), or more than the resource
      // has: then it is not ours and the download starts over.
      const auto range = parse_content_range(content_range);
      if (range && range->total == offset) return true;
      fs::remove(part);
      return false;
    }
    throw error_from_answer(error, what);
  }

  int64_t start = 0;
  int64_t total = -1;
  if (status == 206) {
    const auto range = parse_content_range(content_range);
    if (!range || range->first != offset) {
      connection_->close();
      throw ApiCallError(0, "bad_response",
                         what + ": 206 with Content-Range '" + content_range +
                             "', expected it to start at " + std::to_string(offset));
    }
    start = offset;
    total = range->total;
  } else if (parser.content_length()) {
    total = static_cast<int64_t>(*parser.content_length());
  }
  // 200 after a Range request: the server sent everything, so the part is rewritten.
  FilePtr file = open_part(part, status == 206);
  int64_t done = start;
  try {
    read_body([&](const char* data, size_t n) {
      if (n == 0) return;
      if (std::fwrite(data, 1, n, file.get()) != n)
        throw std::runtime_error(part.string() + ": write failed: " + std::strerror(errno));
      done += static_cast<int64_t>(n);
      stats_.download_body_bytes += static_cast<int64_t>(n);
      if (progress) progress(done, total);
    });
  } catch (...) {
    connection_->close();  // a half-read body would poison the next request
    throw;                 // the part keeps what was written: the next attempt resumes there
  }
  if (std::fflush(file.get()) != 0)
    throw std::runtime_error(part.string() + ": write failed: " + std::strerror(errno));
  return true;
}

void ApiClient::download(const std::string& target, const fs::path& destination,
                         const std::string& expected_sha256, const ProgressFn& progress) {
  const fs::path part = destination.string() + ".part";
  if (destination.has_parent_path()) fs::create_directories(destination.parent_path());
  int failures = 0;
  int restarts = 0;
  while (true) {
    const int64_t before = part_size(part);
    try {
      if (download_once(target, part, progress)) break;
      if (++restarts > 1)
        throw ApiCallError(0, "bad_response", "GET " + target + ": the server refuses every range");
    } catch (const ApiCallError& e) {
      if (e.status() != 0 || e.code() != "transport") throw;
      if (part_size(part) > before) failures = 0;  // progress was made: a new run of failures
      if (++failures > config_.retries)
        throw ApiCallError(
            0, "transport",
            std::string(e.what()) + " (gave up after " + std::to_string(failures) + " attempts)");
      pause_before_retry(failures);
    }
  }
  if (!expected_sha256.empty()) {
    const std::string actual = keel::sha256_file(part);
    if (actual != expected_sha256) {
      fs::remove(part);  // a corrupt part must not be resumed
      throw ApiCallError(0, "sha256_mismatch",
                         "GET " + target + ": downloaded bytes have SHA-256 " + actual +
                             ", expected " + expected_sha256 + " (partial file removed)");
    }
  }
  fs::rename(part, destination);
}

}  // namespace keel::client
