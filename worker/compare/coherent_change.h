// A core point's change is reported significant only where its neighbourhood agrees: |M3C2|
// beyond LoD95 at the core and, with the same sign, at at least half of the defined core
// points within a radius (the core included). LoD95 holds its 95 % at each core alone
// (compare/tile_correction.h calibrates it so), so one core in twenty of unchanged structure
// exceeds it; those exceedances are scattered, while a change covers a patch of cores. The
// radius is the smallest patch reported as change: a change narrower than about twice it is
// not. 0 turns the test off (significant = beyond LoD95).
#pragma once

#include <vector>

#include "worker/compare/m3c2.h"

namespace keel::compare {

// Clears `significant` of the cores whose neighbourhood within radius_m does not agree.
void require_coherent_change(std::vector<CoreChange>* cores, double radius_m, int threads);

}  // namespace keel::compare
