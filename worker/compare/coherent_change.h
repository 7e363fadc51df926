// A core point's change is reported significant only where its neighbourhood agrees: the core
// significant and, with the same sign of change, at least half of the defined core points
// within a radius (the core included). A level of detection holds its confidence at each core
// alone, so a fixed share of the cores of unchanged structure exceeds it, mostly scattered,
// while a change covers a patch of cores. The radius is the smallest patch reported as change:
// a change narrower than about twice it is not. 0 turns the test off.
#pragma once

#include <vector>

#include "worker/compare/m3c2.h"

namespace keel::compare {

// Clears `significant` of the cores whose neighbourhood within radius_m does not agree.
// `significant` is read as set (compare/m3c2.h apply_registration_errors).
void require_coherent_change(std::vector<CoreChange>* cores, double radius_m, int threads);

}  // namespace keel::compare
