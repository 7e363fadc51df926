#include "client/submit.h"

#include <yaml-cpp/yaml.h>

#include <cstdio>

#include "client/bundle_tar.h"
#include "client/local_file_error.h"
#include "client/progress_bar.h"
#include "core/sha256.h"

namespace keel::client {

namespace fs = std::filesystem;

namespace {

// Uploads one file with a progress bar on stderr.
std::string upload_with_progress(ApiClient& api, const fs::path& file, const std::string& label,
                                 const fs::path& state_dir, bool show_progress,
                                 const std::string& known_sha256 = "") {
  ProgressBarOptions bar_options;
  bar_options.terminal = is_terminal(stderr);
  ProgressBar bar(label, bar_options);
  ProgressFn progress;
  if (show_progress)
    progress = [&bar](int64_t done, int64_t total) {
      bar.update(done, total, monotonic_seconds());
    };
  const std::string blob = api.upload_file(file, state_dir, progress, known_sha256);
  if (show_progress) bar.finish(monotonic_seconds());
  return blob;
}

// A mission stored earlier with the same name and blobs (a re-run submit) is reused.
proto::Mission find_or_create_mission(ApiClient& api, const proto::MissionRequest& request) {
  for (const proto::Mission& m : api.list_missions(request.name))
    if (m.name == request.name && m.bundle_blob == request.bundle_blob &&
        m.cad_blob == request.cad_blob && m.cad_name == request.cad_name)
      return m;
  return api.create_mission(request);
}

}  // namespace

std::string submit_idempotency_key(const std::string& bundle_blob, const std::string& cad_blob,
                                   const std::vector<std::string>& stages,
                                   const nlohmann::json& options) {
  const nlohmann::json key = {
      {"bundle", bundle_blob}, {"cad", cad_blob}, {"stages", stages}, {"options", options}};
  return keel::sha256_bytes(key.dump());  // nlohmann sorts object keys: a canonical form
}

std::string mission_name_of(const fs::path& mission_dir) {
  std::error_code ec;
  if (!fs::is_directory(mission_dir, ec))
    throw LocalFileError(mission_dir.string() + ": mission folder not found");
  const fs::path manifest = mission_dir / "mission.yaml";
  if (!fs::is_regular_file(manifest, ec))
    throw LocalFileError(manifest.string() + ": not found (a mission folder holds mission.yaml)");
  try {
    const YAML::Node root = YAML::LoadFile(manifest.string());
    if (root.IsMap() && root["name"] && root["name"].IsScalar())
      return root["name"].as<std::string>();
  } catch (const YAML::Exception& e) {
    throw LocalFileError(manifest.string() + ": " + e.what());
  }
  fs::path dir = fs::absolute(mission_dir).lexically_normal();
  if (dir.filename().empty()) dir = dir.parent_path();  // "folder/" normalises to "folder/"
  return dir.filename().string();
}

SubmitResult submit_mission(ApiClient& api, const SubmitOptions& options) {
  SubmitResult result;
  const std::string manifest_name = mission_name_of(options.mission_dir);  // checks the folder
  const std::string name = options.name.empty() ? manifest_name : options.name;
  std::error_code ec;
  if (!options.cad_file.empty() && !fs::is_regular_file(options.cad_file, ec))
    throw LocalFileError(options.cad_file.string() + ": CAD mesh not found");

  const fs::path state_dir = options.cache_dir / "uploads";
  const fs::path tar = write_bundle_to_cache(options.mission_dir, options.cache_dir / "bundles");
  // The cached tar is named after its SHA-256: no second hashing pass.
  result.bundle_blob = upload_with_progress(api, tar, "bundle " + name, state_dir,
                                            options.show_progress, tar.stem().string());
  fs::remove(tar, ec);  // the server has it; a re-run rebuilds the same bytes
  if (!options.cad_file.empty())
    result.cad_blob =
        upload_with_progress(api, options.cad_file, "cad " + options.cad_file.filename().string(),
                             state_dir, options.show_progress);

  proto::MissionRequest mission_request{
      name, result.bundle_blob, result.cad_blob,
      options.cad_file.empty() ? "" : options.cad_file.filename().string()};
  result.mission = find_or_create_mission(api, mission_request);

  proto::JobRequest job_request{result.mission.id, options.stages, options.options};
  result.job = api.create_job(
      job_request,
      submit_idempotency_key(result.bundle_blob, result.cad_blob, options.stages, options.options));
  return result;
}

}  // namespace keel::client
