// POST /v1/comparisons (issue 16): a `compare` job over two finished jobs of one project. The
// pair is checked here, so a request that cannot be compared is refused with the reason
// instead of becoming a failed job: an unknown (or another project's) job 404, a job not
// succeeded, jobs of two projects, a map job against a hull job 409 `not_comparable`. The job
// runs on B's mission with stages ["compare"] and options {"compare": {...options, "job_a",
// "job_b"}}; the store's lease gives the worker both jobs' records and artifacts
// (Lease::inputs). A reprocess job made with "compare": true has options.compare.job_a
// alone: its lease gives job A, and the stage compares A with the job's own products.
#include "proto/job.h"
#include "server/api_response.h"
#include "server/routes.h"

namespace keel::server::routes {
namespace {

// What a job's artifacts hold, in the words of the refusal.
struct Holds {
  bool maps = false, hull = false;
  std::string words() const {
    if (maps && hull) return "maps and a remeshed hull";
    if (maps) return "maps (stage map)";
    if (hull) return "a remeshed hull (stages ba, inspect)";
    return "neither maps nor a remeshed hull";
  }
};

Holds holds(const std::vector<proto::Artifact>& artifacts) {
  Holds h;
  for (const auto& a : artifacts) {
    const std::string& n = a.name;
    if (n.rfind("map_", 0) == 0 && n.size() > 4 && n.compare(n.size() - 4, 4, ".drc") == 0)
      h.maps = true;
    if (n == "mesh_remeshed.drc") h.hull = true;
  }
  return h;
}

ApiException not_comparable(const std::string& message) {
  return ApiException(409, "not_comparable", message);
}

}  // namespace

Response create_comparison(const Call& call) {
  const proto::ComparisonRequest request =
      proto::ComparisonRequest::from_json(parse_json_body(call.request));
  std::vector<proto::Job> jobs;
  for (const std::string& id : {request.job_a, request.job_b}) {
    proto::Job job = call.store.get_job(id);
    require_reach(call, job.project, "job " + id + " not found");
    jobs.push_back(job);
  }
  const proto::Job &a = jobs[0], &b = jobs[1];
  if (a.project != b.project)
    throw not_comparable("job " + a.id + " belongs to project '" + a.project + "' and job " + b.id +
                         " to project '" + b.project +
                         "': only jobs of one project can be compared");
  for (const proto::Job& job : jobs)
    if (job.state != proto::JobState::kSucceeded)
      throw not_comparable("job " + job.id + " is " + proto::to_string(job.state) +
                           ": only finished (succeeded) jobs can be compared");
  const Holds ha = holds(call.store.list_artifacts(a.id)),
              hb = holds(call.store.list_artifacts(b.id));
  const bool maps = ha.maps && hb.maps, hull = ha.hull && hb.hull;
  if (!maps && !hull && a.mission_id != b.mission_id)
    throw not_comparable("job " + a.id + " holds " + ha.words() + " and job " + b.id + " " +
                         hb.words() + ": a map compares with a map, a hull with a hull");

  proto::JobRequest job;
  job.mission_id = b.mission_id;
  job.stages = {"compare"};
  nlohmann::json options = request.options;
  options["job_a"] = a.id;
  options["job_b"] = b.id;
  job.options = {{"compare", options}};
  job.project = a.project;
  const std::string key = idempotency_key(call.request);
  bool created = true;
  const proto::Job made = call.store.create_job(job, key, &created);
  return json_response(created ? 201 : 200, made.to_json());
}

}  // namespace keel::server::routes
