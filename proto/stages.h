// The stages Keel knows, in pipeline order: the one list of their names. The server and the
// CLI check job requests against it (proto/options.h); the worker's registry expands it into
// one entry per stage, `make_<name>_stage()` of worker/stages/<name>/stage.h
// (worker/pipeline/stage_registry.cc). A new stage is one X(...) here and its folder.
#pragma once

#define KEEL_STAGES(X) X(ingest) X(refine) X(calibrate) X(map) X(ba) X(inspect) X(compare)
