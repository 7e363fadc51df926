// Stage `compare` (issue 16): what changed between two finished jobs of the same structure,
// A (earlier) and B (later), given as StageContext::input_jobs. Its steps are in stage.cc;
// its options in options.h; the files it writes in artifacts.h.
#pragma once

#include "worker/pipeline/stage.h"
#include "worker/stages/compare/artifacts.h"
#include "worker/stages/compare/options.h"
