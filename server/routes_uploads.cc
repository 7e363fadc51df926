// Resumable uploads (POST/HEAD/GET/PUT/DELETE /v1/uploads...) and GET /v1/blobs/{sha256}.
#include "proto/contract_error.h"
#include "proto/resources.h"
#include "server/api_response.h"
#include "server/byte_range.h"
#include "server/file_response.h"
#include "server/routes.h"

namespace keel::server::routes {

namespace {

ApiException offset_mismatch(int64_t committed, const std::string& detail) {
  Headers headers;
  headers.set("Upload-Offset", std::to_string(committed));
  return ApiException(409, "offset_mismatch",
                      detail + "; resume from offset " + std::to_string(committed), headers);
}

ApiException bad_range(const std::string& message) {
  return ApiException(416, "bad_range", message);
}

// The upload, when the token reaches its project (404 otherwise, as for an unknown id).
proto::Upload reachable_upload(const Call& call, const std::string& upload_id) {
  proto::Upload upload = call.store.get_upload(upload_id);
  require_reach(call, upload.project, "upload " + upload_id + " not found");
  return upload;
}

}  // namespace

Response create_upload(const Call& call) {
  proto::UploadRequest request = proto::UploadRequest::from_json(parse_json_body(call.request));
  if (request.size < 0)
    throw ApiException(400, "invalid_field", "size: expected a byte count >= 0");
  request.project = request_project(call, request.project);
  require_quota(call, request.project, request.size, "upload '" + request.name + "'");
  require_space(call, request.size, "upload '" + request.name + "'");
  return json_response(201, call.store.create_upload(request).to_json());
}

Response head_upload(const Call& call) {
  proto::Upload upload = reachable_upload(call, call.params[0]);
  Response response = empty_response(200);
  response.headers.set("Upload-Offset", std::to_string(upload.offset));
  response.headers.set("Upload-Length", std::to_string(upload.size));
  response.headers.set("Cache-Control", "no-store");
  return response;
}

Response get_upload(const Call& call) {
  return json_response(200, reachable_upload(call, call.params[0]).to_json());
}

// A chunk is `Content-Range: bytes a-b/N` with exactly b-a+1 body bytes, N the announced
// size and a the committed offset. The store appends it whole (fsync) or not at all.
Response put_upload_chunk(const Call& call) {
  const std::string& id = call.params[0];
  auto header = call.request.headers.get("Content-Range");
  if (!header) throw bad_range("Content-Range: missing (expected 'bytes a-b/N')");
  std::optional<ContentRange> range = parse_content_range(*header);
  if (!range)
    throw bad_range("Content-Range '" + *header + "': expected 'bytes a-b/N' with a <= b < N");
  const int64_t body_size = static_cast<int64_t>(call.request.body.size());
  if (range->length() != body_size)
    throw bad_range("Content-Range '" + *header + "' announces " + std::to_string(range->length()) +
                    " bytes but the body has " + std::to_string(body_size));
  proto::Upload upload = reachable_upload(call, id);
  if (range->total != upload.size)
    throw bad_range("Content-Range '" + *header + "': total " + std::to_string(range->total) +
                    " differs from the upload's announced size " + std::to_string(upload.size));
  if (range->first != upload.offset)
    throw offset_mismatch(upload.offset, "chunk starts at " + std::to_string(range->first) +
                                             " but " + std::to_string(upload.offset) +
                                             " bytes are committed");
  require_space(call, body_size, "chunk of upload " + id);
  try {
    upload = call.store.append_upload(id, range->first, call.request.body.data(),
                                      call.request.body.size());
  } catch (const storage::OffsetMismatch& e) {
    // Another chunk of the same upload won the race; tell where it ended.
    throw offset_mismatch(e.committed_offset, e.what());
  }
  Response response = json_response(200, upload.to_json());
  response.headers.set("Upload-Offset", std::to_string(upload.offset));
  return response;
}

// {"sha256": "<hex>"} -> 200 {"blob", "size"}; 422 and the upload deleted when the bytes
// committed do not match.
Response complete_upload(const Call& call) {
  nlohmann::json body = parse_json_body(call.request);
  proto::FieldReader reader(body, "");
  reader.reject_unknown({"sha256"});
  std::string sha256 = reader.required<std::string>("sha256");
  if (!proto::is_sha256_hex(sha256))
    throw ApiException(400, "invalid_field", "sha256: expected 64 lowercase hex digits");
  proto::Upload upload = reachable_upload(call, call.params[0]);
  std::string blob;
  try {
    blob = call.store.complete_upload(upload.id, sha256);
  } catch (const storage::SizeMismatch& e) {
    throw ApiException(422, "size_mismatch", e.what());
  } catch (const storage::Sha256Mismatch& e) {
    throw ApiException(422, "sha256_mismatch", e.what());
  }
  return json_response(200, {{"blob", blob}, {"size", upload.size}});
}

Response delete_upload(const Call& call) {
  reachable_upload(call, call.params[0]);
  call.store.delete_upload(call.params[0]);
  return empty_response(204);
}

Response get_blob(const Call& call) {
  const std::string& sha256 = call.params[0];
  if (!proto::is_sha256_hex(sha256))
    throw ApiException(404, "not_found",
                       "blob '" + sha256 + "': not a SHA-256 (64 lowercase hex digits)");
  // A token of one project fetches only the blobs its project references: a hash must not
  // tell whether another project holds some content.
  if (!call.principal.all_projects() &&
      !call.store.project_has_blob(call.principal.project, sha256))
    throw ApiException(404, "not_found", "blob " + sha256 + " not found");
  StoredFile file;
  file.path = call.store.blob_path(sha256);
  file.size = static_cast<uint64_t>(call.store.blob_size(sha256));
  file.sha256 = sha256;
  return file_response(call.request, file);
}

}  // namespace keel::server::routes
