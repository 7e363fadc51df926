// How far a reprocess batch is (`keel jobs --batch ID`): counts by state and an ETA.
#pragma once

#include <optional>
#include <string>

#include "proto/job.h"

namespace keel::client {

// Seconds until the batch's queued and running jobs are done, assuming jobs keep taking
// the batch's mean time so far (mean_job_seconds) and as many run at once as run now:
//   ETA = mean * (queued + running / 2) / running
// (a running job is taken as half done). nullopt while no job has finished (no mean yet)
// or none runs (no pace); 0 when nothing is left.
std::optional<double> batch_eta_seconds(const proto::Batch& batch);

// "1h 02m", "4m 05s", "12s".
std::string format_duration_s(double seconds);

// Two lines: the counts by state, then the mean job time and the ETA (or why there is none).
std::string format_batch_status(const proto::Batch& batch);

// True when no job of the batch is queued or running.
bool batch_finished(const proto::Batch& batch);

}  // namespace keel::client
