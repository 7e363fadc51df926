// Human-readable text of jobs and missions for the `keel` CLI.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "proto/job.h"
#include "proto/resources.h"

namespace keel::client {

// "2024-05-01 12:03:04Z" (UTC) for epoch milliseconds; "-" for 0.
std::string format_time_ms(int64_t t_ms);

// Columns padded to their widest cell, two spaces apart, first row = header.
std::string format_table(const std::vector<std::vector<std::string>>& rows);

// ID STATE STAGE PROGRESS MISSION CREATED
std::string format_job_table(const std::vector<proto::Job>& jobs);
// ID NAME BUNDLE CAD CREATED
std::string format_mission_table(const std::vector<proto::Mission>& missions);
// Several "key: value" lines: state, stage and progress, stages, timings, error.
std::string format_job_status(const proto::Job& job);

}  // namespace keel::client
