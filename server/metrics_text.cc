#include "server/metrics_text.h"

#include <sstream>

#include "proto/job.h"

namespace keel::server {

namespace {

void family(std::ostringstream& out, const char* name, const char* type, const char* help) {
  out << "# HELP " << name << ' ' << help << '\n' << "# TYPE " << name << ' ' << type << '\n';
}

}  // namespace

std::string render_metrics(const storage::Metrics& m, const RequestCounters& counters,
                           int workers_alive) {
  std::ostringstream out;
  family(out, "keel_jobs", "gauge", "Jobs by state.");
  for (int state = 0; state < 5; ++state)
    out << "keel_jobs{state=\"" << proto::to_string(static_cast<proto::JobState>(state)) << "\"} "
        << m.jobs_by_state[state] << '\n';
  family(out, "keel_missions", "gauge", "Stored missions.");
  out << "keel_missions " << m.missions << '\n';
  family(out, "keel_blobs", "gauge", "Content-addressed blobs stored.");
  out << "keel_blobs " << m.blobs << '\n';
  family(out, "keel_blob_bytes", "gauge", "Bytes held by stored blobs.");
  out << "keel_blob_bytes " << m.blob_bytes << '\n';
  family(out, "keel_uploads_open", "gauge", "Resumable uploads not completed yet.");
  out << "keel_uploads_open " << m.uploads_open << '\n';
  family(out, "keel_http_requests_total", "counter", "HTTP requests answered, by status class.");
  for (int digit = 1; digit <= 5; ++digit)
    out << "keel_http_requests_total{code=\"" << digit << "xx\"} " << counters.by_class(digit)
        << '\n';
  family(out, "keel_workers_alive", "gauge",
         "Local keel-worker processes the server supervises that are running.");
  out << "keel_workers_alive " << workers_alive << '\n';
  return out.str();
}

}  // namespace keel::server
