// Stage `ingest`: validates the mission bundle and reports what it holds (streams, rates,
// time spans, gaps, point and image counts) as its section of report.json.
#pragma once

#include <memory>

#include "worker/pipeline/stage.h"

namespace keel::pipeline {


}  // namespace keel::pipeline
