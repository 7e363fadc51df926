// A keel-sim mission for the stage tests, written by the simulator library.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "tests/sim/simulator.h"

namespace keel::pipeline::testing {

// Writes `scenario` with `seed` into `dir` and returns `dir`: `duration_s` <= 0 is the
// scenario's whole path, no `sensors` all of them (sim::SimOptions).
inline std::filesystem::path simulate(const std::filesystem::path& dir, const std::string& scenario,
                                      uint64_t seed, double duration_s = 0.0,
                                      std::vector<std::string> sensors = {}) {
  sim::SimOptions o;
  o.scenario = scenario;
  o.seed = seed;
  o.out_dir = dir.string();
  o.duration_s = duration_s;
  o.sensors = std::move(sensors);
  sim::run_simulation(o);
  return dir;
}

}  // namespace keel::pipeline::testing
