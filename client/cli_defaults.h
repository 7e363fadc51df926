// Defaults of the `keel` CLI, in one place.
#pragma once

namespace keel::client {

// Stages a submit or reprocess runs when --stages is not given. Later pipeline stages
// join this list as they become available.
inline constexpr const char* kDefaultStages = "ingest";

// Seconds between polls of `watch`, `log --follow` and `submit --wait`.
inline constexpr double kDefaultPollInterval_s = 1.0;

}  // namespace keel::client
