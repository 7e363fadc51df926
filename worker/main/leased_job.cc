#include "worker/main/leased_job.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <system_error>
#include <thread>

#include "worker/main/job_heartbeat.h"
#include "worker/pipeline/bundle_unpack.h"
#include "worker/pipeline/report.h"

namespace keel::worker {

namespace fs = std::filesystem;

namespace {

// Errors of the server or the link, not of the job: the job is abandoned and its lease
// expires, so it is retried later (by this or another worker). Not 507 insufficient_storage:
// a server that cannot store the products refuses every attempt alike, and three expired
// leases would fail the job as "lease expired 3 times", hiding the server's own words (which
// say how full its disk is). The job fails with them; the user reprocesses it once space is
// freed.
bool is_server_trouble(const client::ApiCallError& e) {
  if (e.status() == 507) return false;
  return e.status() == 0 || e.status() == 408 || e.status() == 409 || e.status() == 429 ||
         e.status() >= 500;
}

// A name the server sent that becomes a file name here must be a plain file name.
std::string plain_file_name(const std::string& name, const std::string& what) {
  if (name.empty() || name == "." || name == ".." || name.find('/') != std::string::npos ||
      name.find('\\') != std::string::npos)
    throw std::invalid_argument(what + " '" + name + "' is not a plain file name");
  return name;
}

// Raised when the job must stop without reporting anything more.
struct Abandon {
  std::string why;
};

// The worker's disk budget for a bundle: at most 90% of what the job folder's disk has free
// (the stages' outputs need the rest), so a bundle that does not fit is refused while
// unpacking, before the disk is full, and the partial folder is removed.
pipeline::UnpackLimits unpack_budget(const fs::path& job_dir) {
  pipeline::UnpackLimits limits;
  std::error_code error;
  const fs::space_info space = fs::space(job_dir, error);
  if (!error)
    limits.max_total_bytes =
        std::min(limits.max_total_bytes, static_cast<int64_t>(space.available / 10 * 9));
  return limits;
}

}  // namespace

std::string to_string(JobEnd end) {
  switch (end) {
    case JobEnd::kSucceeded:
      return "succeeded";
    case JobEnd::kFailed:
      return "failed";
    case JobEnd::kCanceled:
      return "canceled";
    case JobEnd::kAbandoned:
      return "abandoned";
    case JobEnd::kReleased:
      return "released";
  }
  return "unknown";
}

LeasedJob::LeasedJob(client::ApiClient& api, client::ApiClient& heartbeat_api, BlobCache& blobs,
                     const proto::Lease& lease, const LeasedJobOptions& options,
                     pipeline::StageFactory factory, std::function<bool()> stop_requested)
    : api_(api),
      heartbeat_api_(heartbeat_api),
      blobs_(blobs),
      lease_(lease),
      options_(options),
      factory_(std::move(factory)),
      stop_requested_(std::move(stop_requested)) {}

void LeasedJob::log(const std::string& line) {
  spdlog::info("job {}: {}", lease_.job.id, line);
  if (heartbeat_) heartbeat_->log(line);
}

JobEnd LeasedJob::run() {
  const proto::Job& job = lease_.job;
  JobHeartbeat heartbeat(heartbeat_api_, job.id, lease_.lease_id, options_.heartbeat_seconds);
  heartbeat_ = &heartbeat;
  for (const auto& stage : job.stages) {
    if (std::find(job.completed_stages.begin(), job.completed_stages.end(), stage) ==
        job.completed_stages.end()) {
      heartbeat.set_stage(stage);
      break;
    }
  }
  heartbeat.start();

  JobEnd end = JobEnd::kAbandoned;
  try {
    job_dir_ = options_.jobs_dir / plain_file_name(job.id, "job id");
    work_dir_ = job_dir_ / "work";
    log("leased (attempt " + std::to_string(job.attempts) + ", stages " +
        std::to_string(job.stages.size()) + ", " + std::to_string(lease_.completed.size()) +
        " completed earlier)");
    const pipeline::JobSpec spec = prepare();

    pipeline::JobHooks hooks;
    hooks.on_stage_start = [&](const std::string& stage) { heartbeat.set_stage(stage); };
    hooks.progress = [&](const std::string&, double p) { heartbeat.set_progress(p); };
    hooks.log = [&](const std::string& line) { log(line); };
    hooks.canceled = [&] {
      return heartbeat.canceled() || heartbeat.lease_lost() || stop_requested_();
    };
    hooks.on_stage_done = [&](const std::string& stage, const pipeline::StageResult& result,
                              double seconds) { on_stage_done(stage, result, seconds); };
    const pipeline::JobResult result = pipeline::JobRunner(factory_).run(spec, hooks);
    heartbeat.stop();
    end = finish(result);
  } catch (const Abandon& a) {
    heartbeat.stop();
    end = heartbeat.canceled()                           ? JobEnd::kCanceled
          : stop_requested_() && !heartbeat.lease_lost() ? give_back(a.why)
                                                         : abandon(a.why);
  } catch (const client::ApiCallError& e) {
    heartbeat.stop();
    if (heartbeat.lease_lost())
      end = abandon(std::string("server: ") + e.what());
    else if (is_server_trouble(e))
      end = stop_requested_() ? give_back(std::string("server: ") + e.what())
                              : abandon(std::string("server: ") + e.what());
    else
      end = fail(e.what());
  } catch (const std::exception& e) {
    heartbeat.stop();
    end = heartbeat.lease_lost() ? abandon(e.what())
          : stop_requested_()    ? give_back(e.what())
                                 : fail(e.what());
  }
  heartbeat_ = nullptr;

  if (!options_.keep_work && !job_dir_.empty()) {
    std::error_code ec;
    fs::remove_all(job_dir_, ec);
    if (ec) spdlog::warn("job {}: cannot remove {}: {}", job.id, job_dir_.string(), ec.message());
  }
  spdlog::info("job {}: {}", job.id, to_string(end));
  return end;
}

pipeline::JobSpec LeasedJob::prepare() {
  auto check_stop = [this](const char* step) {
    if (heartbeat_->canceled()) throw Abandon{std::string("canceled during ") + step};
    if (heartbeat_->lease_lost()) throw Abandon{std::string("lease lost during ") + step};
    if (stop_requested_()) throw Abandon{std::string("stopping during ") + step};
  };
  if (lease_.job.stages.empty()) throw std::invalid_argument("the job has no stages");
  std::error_code ec;
  fs::remove_all(job_dir_, ec);  // a folder left by an earlier attempt on this machine
  fs::create_directories(work_dir_);

  pipeline::JobSpec spec;
  spec.job = lease_.job.to_json();
  spec.report_job = {{"id", lease_.job.id},
                     {"mission_id", lease_.job.mission_id},
                     {"stages", lease_.job.stages},
                     {"options", lease_.job.options},
                     {"attempts", lease_.job.attempts}};
  spec.report_mission = lease_.mission.to_json();
  const proto::Mission& mission = lease_.mission;

  // A compare job reads two finished jobs' artifacts, not the mission (issue 16).
  const bool compare_only =
      std::all_of(lease_.job.stages.begin(), lease_.job.stages.end(),
                  [](const std::string& stage) { return stage == "compare"; });
  for (size_t i = 0; i < lease_.inputs.size(); ++i) {
    const proto::LeaseInput& input = lease_.inputs[i];
    pipeline::InputJob job;
    job.dir = job_dir_ / (i == 0 ? "input_a" : "input_b");
    job.job = input.job.to_json();
    fs::create_directories(job.dir);
    log("fetching " + std::to_string(input.artifacts.size()) + " artifacts of job " + input.job.id);
    for (const auto& artifact : input.artifacts)
      api_.download("/v1/artifacts/" + artifact.id,
                    job.dir / plain_file_name(artifact.name, "artifact name"), artifact.sha256);
    check_stop("input download");
    spec.input_jobs.push_back(std::move(job));
  }

  if (!compare_only) {
    log("fetching mission bundle " + mission.bundle_blob);
    const fs::path bundle = blobs_.fetch(api_, mission.bundle_blob);
    check_stop("bundle download");
    try {
      spec.mission_dir =
          pipeline::unpack_bundle(bundle, job_dir_ / "mission", unpack_budget(job_dir_));
    } catch (const pipeline::BundleError& e) {
      // Name the bundle by its blob id, not by this worker's cache path.
      std::string message = e.what();
      const std::string prefix = bundle.string() + ": ";
      if (message.rfind(prefix, 0) == 0) message = message.substr(prefix.size());
      throw std::runtime_error("mission bundle " + mission.bundle_blob + ": " + message);
    }
    check_stop("bundle unpack");
  }

  if (!compare_only && !mission.cad_blob.empty()) {
    log("fetching CAD mesh " + mission.cad_blob);
    const fs::path cad = blobs_.fetch(api_, mission.cad_blob);
    const std::string name =
        plain_file_name(mission.cad_name.empty() ? "cad.ply" : mission.cad_name, "cad_name");
    fs::create_directories(job_dir_ / "cad");
    spec.cad_path = job_dir_ / "cad" / name;
    // The extension tells readers the format; a hard link avoids copying a large mesh.
    fs::create_hard_link(cad, spec.cad_path, ec);
    if (ec) fs::copy_file(cad, spec.cad_path);
    check_stop("CAD download");
  }

  download_completed_artifacts(work_dir_);
  check_stop("artifact download");

  spec.work_dir = work_dir_;
  spec.stages = lease_.job.stages;
  spec.options = lease_.job.options;
  for (const auto& output : lease_.completed) {
    spec.completed.push_back({output.stage, output.report, output.seconds});
  }
  return spec;
}

void LeasedJob::download_completed_artifacts(const fs::path& work_dir) {
  for (const auto& output : lease_.completed) {
    for (const auto& artifact : output.artifacts) {
      const std::string name = plain_file_name(artifact.name, "artifact name");
      log("resuming: fetching " + output.stage + " artifact " + name);
      api_.download("/v1/artifacts/" + artifact.id, work_dir / name, artifact.sha256);
    }
  }
}

void LeasedJob::on_stage_done(const std::string& stage, const pipeline::StageResult& result,
                              double seconds) {
  for (const auto& name : result.artifacts) upload_artifact(stage, name);
  proto::StageCompletion completion;
  completion.lease_id = lease_.lease_id;
  completion.report = result.report;
  completion.seconds = seconds;
  api_.complete_stage(lease_.job.id, stage, completion);
  log(stage + ": completion posted");
}

void LeasedJob::upload_artifact(const std::string& stage, const std::string& name) {
  const fs::path file = work_dir_ / name;
  const std::string blob = api_.upload_file(file, options_.uploads_dir, {}, "", lease_.job.project);
  proto::ArtifactRegistration registration;
  registration.lease_id = lease_.lease_id;
  registration.stage = stage;
  registration.name = name;
  registration.blob = blob;
  api_.register_artifact(lease_.job.id, registration);
  log(stage + ": uploaded " + name + " (" + std::to_string(fs::file_size(file)) + " bytes)");
}

// report.json and report.html written by the runner outside a stage's artifacts (a failed
// job's, or a job whose stages all finished earlier), uploaded under the last stage as a
// finished job's report is: a retry that succeeds replaces them.
void LeasedJob::upload_report_files(const pipeline::JobResult& result) {
  if (!result.report_error.empty()) {
    log("could not write the job's report: " + result.report_error);
    return;
  }
  try {
    for (const auto& name : result.report_files) upload_artifact(lease_.job.stages.back(), name);
  } catch (const std::exception& e) {
    // A failure itself still gets posted; its report is a courtesy.
    if (result.outcome != pipeline::JobOutcome::kFailed) throw;
    log("could not upload the failed job's report: " + std::string(e.what()));
  }
}

JobEnd LeasedJob::finish(const pipeline::JobResult& result) {
  switch (result.outcome) {
    case pipeline::JobOutcome::kCanceled:
      if (heartbeat_->lease_lost()) return abandon("lease lost");
      if (heartbeat_->canceled()) return JobEnd::kCanceled;  // the server knows; say nothing more
      return give_back("worker stopping");
    case pipeline::JobOutcome::kFailed:
      if (!lease_.job.stages.empty()) upload_report_files(result);
      return fail(result.error);
    case pipeline::JobOutcome::kSucceeded:
      break;
  }
  // Every stage was completed by earlier attempts: the report is not among any stage's.
  upload_report_files(result);
  if (!heartbeat_->flush(api_) && heartbeat_->lease_lost()) return abandon("lease lost");
  proto::JobFinish finish;
  finish.lease_id = lease_.lease_id;
  api_.finish_job(lease_.job.id, finish, /*succeeded=*/true);
  return JobEnd::kSucceeded;
}

JobEnd LeasedJob::fail(const std::string& error) {
  spdlog::error("job {}: failed: {}", lease_.job.id, error);
  if (heartbeat_) heartbeat_->flush(api_);
  proto::JobFinish finish;
  finish.lease_id = lease_.lease_id;
  finish.error = error;
  try {
    api_.finish_job(lease_.job.id, finish, /*succeeded=*/false);
  } catch (const std::exception& e) {
    // The lease will expire and the job be retried; nothing else to do from here.
    spdlog::error("job {}: could not post the failure: {}", lease_.job.id, e.what());
    return JobEnd::kAbandoned;
  }
  return JobEnd::kFailed;
}

JobEnd LeasedJob::give_back(const std::string& why) {
  if (heartbeat_) heartbeat_->flush(api_);  // the log lines so far, before the lease goes
  // A stop often comes with the server's own end: a local worker stops when keel-server dies
  // (PR_SET_PDEATHSIG), and a restarted server is back within seconds. A released job is
  // queued at once and keeps its retry budget; an expired lease counts toward the "lease
  // expired 3 times" failure, so a server killed three times during one job failed it (the
  // crash torture test, on a loaded machine). Until the lease would have run out anyway, an
  // unreachable or failing server is asked again.
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(options_.lease_seconds);
  auto pause = std::chrono::milliseconds(100);
  for (;;) {
    try {
      api_.release_job(lease_.job.id, lease_.lease_id);
      break;
    } catch (const client::ApiCallError& e) {
      const bool server_away = e.status() == 0 || e.status() >= 500;
      if (!server_away || std::chrono::steady_clock::now() + pause >= deadline)
        return abandon(std::string(why) + "; giving the lease back failed: " + e.what());
    } catch (const std::exception& e) {
      return abandon(std::string(why) + "; giving the lease back failed: " + e.what());
    }
    std::this_thread::sleep_for(pause);
    pause = std::min(2 * pause, std::chrono::milliseconds(1000));
  }
  spdlog::info("job {}: lease given back ({}); the job is queued again", lease_.job.id, why);
  return JobEnd::kReleased;
}

JobEnd LeasedJob::abandon(const std::string& why) {
  spdlog::warn("job {}: abandoned ({}); its lease will expire", lease_.job.id, why);
  return JobEnd::kAbandoned;
}

}  // namespace keel::worker
