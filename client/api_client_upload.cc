// ApiClient::upload_file: resumable chunked upload (docs/api.md "Uploads").
//   1. hash the file; the state file `upload-<sha256>-<size>.id` in state_dir names the
//      upload started by an earlier run, if any;
//   2. HEAD the upload for its committed offset (404: start a new upload);
//   3. PUT chunks with Content-Range from that offset; on a dropped link or 409
//      offset_mismatch ask the offset again and go on (config.retries consecutive failures);
//   4. complete with the SHA-256 → blob, delete the state file.
#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <vector>

#include "client/api_client.h"
#include "client/api_client_connection.h"
#include "client/http_ranges.h"
#include "proto/resources.h"
#include "core/sha256.h"

namespace keel::client {

namespace fs = std::filesystem;

namespace {

std::runtime_error file_error(const fs::path& file, const std::string& what) {
  return std::runtime_error(file.string() + ": " + what);
}

// A read-only file descriptor that closes itself.
class InputFile {
 public:
  explicit InputFile(const fs::path& file) : path_(file), fd_(::open(file.c_str(), O_RDONLY)) {
    if (fd_ < 0) throw file_error(file, std::string("cannot open: ") + std::strerror(errno));
  }
  ~InputFile() { ::close(fd_); }
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;

  // Reads exactly `size` bytes at `offset` into `out`.
  void read_at(char* out, int64_t size, int64_t offset) const {
    while (size > 0) {
      const ssize_t n = ::pread(fd_, out, static_cast<size_t>(size), offset);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) throw file_error(path_, std::string("read failed: ") + std::strerror(errno));
      if (n == 0) throw file_error(path_, "file shrank while uploading it");
      out += n;
      size -= n;
      offset += n;
    }
  }

 private:
  fs::path path_;
  int fd_;
};

std::string read_state(const fs::path& state_file) {
  std::ifstream in(state_file);
  std::string id;
  if (in) std::getline(in, id);
  return id;
}

void write_state(const fs::path& state_file, const std::string& upload_id) {
  const fs::path tmp = state_file.string() + ".tmp";
  {
    std::ofstream out(tmp, std::ios::trunc);
    out << upload_id << "\n";
    if (!out) throw file_error(tmp, "cannot write upload state");
  }
  fs::rename(tmp, state_file);
}

int64_t header_int(const HttpResult& result, const std::string& name, const std::string& what) {
  const auto it = result.headers.find(name);
  try {
    if (it != result.headers.end()) return std::stoll(it->second);
  } catch (const std::exception&) {
  }
  throw ApiCallError(0, "bad_response", what + ": missing or malformed " + name + " header");
}

bool is_transport(const ApiCallError& e) { return e.status() == 0 && e.code() == "transport"; }

}  // namespace

std::optional<int64_t> ApiClient::upload_offset(const std::string& upload_id) {
  const std::string target = "/v1/uploads/" + upload_id;
  const HttpResult result = request("HEAD", target);
  if (result.status == 404) return std::nullopt;
  if (result.status != 200) throw error_from_answer(result, connection_->describe("HEAD", target));
  return header_int(result, "upload-offset", connection_->describe("HEAD", target));
}

std::string ApiClient::create_upload(const std::string& name, int64_t size,
                                     const std::string& project) {
  proto::UploadRequest request{name, size, project};
  const nlohmann::json body = post_json("/v1/uploads", request.to_json());
  try {
    return proto::Upload::from_json(body).id;
  } catch (const std::exception& e) {
    throw ApiCallError(0, "bad_response", std::string("POST /v1/uploads: ") + e.what());
  }
}

bool ApiClient::blob_exists(const std::string& sha256) {
  // Saves a re-upload when the same bytes were sent before (a submit re-run after its
  // uploads completed). One byte is asked for: 206 means the blob is there, 416 that it is
  // there and empty; anything else (404) means "upload it".
  const int status = request("GET", "/v1/blobs/" + sha256, "", {{"Range", "bytes=0-0"}}).status;
  return status == 206 || status == 416;
}

HttpResult ApiClient::put_chunk(const std::string& upload_id, const char* data, int64_t first,
                                int64_t size, int64_t total) {
  const std::string target = connection_->target("/v1/uploads/" + upload_id);
  // span_body sends straight from the chunk buffer: no copy into a string.
  http::request<http::span_body<const char>> req{http::verb::put, target, 11};
  connection_->prepare(req,
                       {{"Content-Type", "application/octet-stream"},
                        {"Content-Range", content_range_header(first, first + size - 1, total)}});
  req.body() = boost::beast::span<const char>(data, static_cast<size_t>(size));
  req.prepare_payload();
  http::response<http::string_body> response = connection_->exchange(req);
  stats_.upload_body_bytes += size;
  HttpResult out;
  out.status = static_cast<int>(response.result_int());
  for (const auto& field : response) {
    std::string name(field.name_string());
    for (auto& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    out.headers[name] = std::string(field.value());
  }
  out.body = std::move(response.body());
  return out;
}

std::string ApiClient::upload_file(const fs::path& file, const fs::path& state_dir,
                                   const ProgressFn& progress, const std::string& known_sha256,
                                   const std::string& project) {
  std::error_code ec;
  const auto size_or_error = fs::file_size(file, ec);
  if (ec) throw file_error(file, "cannot read: " + ec.message());
  const int64_t size = static_cast<int64_t>(size_or_error);
  if (!known_sha256.empty() && !proto::is_sha256_hex(known_sha256))
    throw std::invalid_argument("upload_file: known_sha256 '" + known_sha256 +
                                "' is not 64 lowercase hex digits");
  const std::string sha = known_sha256.empty() ? keel::sha256_file(file) : known_sha256;
  fs::create_directories(state_dir, ec);
  if (ec) throw file_error(state_dir, "cannot create upload state folder: " + ec.message());
  const fs::path state_file = state_dir / ("upload-" + sha + "-" + std::to_string(size) + ".id");

  if (blob_exists(sha)) {
    fs::remove(state_file, ec);
    if (progress) progress(size, size);
    return sha;
  }

  // Step 2: resume a known upload at its committed offset, or start one.
  std::string upload_id = read_state(state_file);
  std::optional<int64_t> offset;
  if (!upload_id.empty()) offset = upload_offset(upload_id);
  if (!offset || *offset > size) {
    upload_id = create_upload(file.filename().string(), size, project);
    write_state(state_file, upload_id);
    offset = 0;
  }
  if (progress) progress(*offset, size);

  // Step 3: chunks from the committed offset.
  const InputFile input(file);
  const int64_t chunk_bytes = std::max<int64_t>(1, config_.chunk_bytes);
  std::vector<char> buffer(static_cast<size_t>(std::min(chunk_bytes, std::max<int64_t>(size, 1))));
  int failures = 0;
  auto fail_once = [&](const std::string& why) {
    if (++failures > config_.retries)
      throw ApiCallError(0, "transport",
                         "upload of " + file.string() + " failed " + std::to_string(failures) +
                             " times in a row: " + why);
    pause_before_retry(failures);
  };
  while (*offset < size) {
    const int64_t n = std::min<int64_t>(static_cast<int64_t>(buffer.size()), size - *offset);
    input.read_at(buffer.data(), n, *offset);
    try {
      const HttpResult result = put_chunk(upload_id, buffer.data(), *offset, n, size);
      if (result.status == 200) {
        offset = proto::Upload::from_json(nlohmann::json::parse(result.body)).offset;
        failures = 0;
        if (progress) progress(*offset, size);
        continue;
      }
      const ApiCallError error = error_from_answer(result, "PUT /v1/uploads/" + upload_id);
      if (result.status == 404) {  // expired or deleted on the server: start over
        fail_once(error.what());
        upload_id = create_upload(file.filename().string(), size, project);
        write_state(state_file, upload_id);
        offset = 0;
        continue;
      }
      if (result.status != 409 && result.status < 500) throw error;
      fail_once(error.what());
      const auto named = result.headers.find("upload-offset");  // a 409 names the offset
      if (result.status == 409 && named != result.headers.end()) {
        offset = header_int(result, "upload-offset", "PUT /v1/uploads/" + upload_id);
      } else {
        offset = upload_offset(upload_id).value_or(0);
      }
    } catch (const ApiCallError& e) {
      if (!is_transport(e)) throw;
      fail_once(e.what());
      // The chunk may or may not have been committed: the server's offset decides.
      while (true) {
        try {
          offset = upload_offset(upload_id).value_or(0);
          break;
        } catch (const ApiCallError& again) {
          if (!is_transport(again)) throw;
          fail_once(again.what());
        }
      }
    } catch (const nlohmann::json::exception& e) {
      throw ApiCallError(0, "bad_response", "PUT /v1/uploads/" + upload_id + ": " + e.what());
    }
  }

  // Step 4: the server checks the SHA-256 and keeps one blob per content.
  const nlohmann::json done =
      post_json("/v1/uploads/" + upload_id + "/complete", nlohmann::json{{"sha256", sha}});
  const std::string blob = done.value("blob", "");
  if (blob != sha)
    throw ApiCallError(0, "bad_response",
                       "POST /v1/uploads/" + upload_id + "/complete: blob '" + blob +
                           "' differs from the file's SHA-256 " + sha);
  fs::remove(state_file, ec);
  return blob;
}

}  // namespace keel::client
