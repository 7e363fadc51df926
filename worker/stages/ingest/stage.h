// Stage `ingest`: validates the mission bundle and reports what it holds (streams, rates,
// time spans, gaps, point and image counts) as its section of report.json. Made by
// make_ingest_stage() (worker/pipeline/stage.h); its options in options.h, the report of each
// part of the bundle in mission_report.h.
#pragma once

#include "worker/pipeline/stage.h"
#include "worker/stages/ingest/options.h"
