// Seeded, platform-independent random numbers for the simulator.
//
// Every stream (sensor, sweep, frame) gets its own generator derived from (seed, stream,
// index), so results do not depend on thread scheduling or on which sensors are enabled.
// The Gaussian sampler is our own Box-Muller: std::normal_distribution is
// implementation-defined and would break "same seed, same bytes" across standard libraries.
#pragma once

#include <cmath>
#include <cstdint>

namespace keel::sim {

inline uint64_t splitmix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

// Stream ids (kept stable: changing them changes every mission's bytes).
enum class Stream : uint64_t {
  kScene = 1,
  kMotion,
  kImu,
  kDvl,
  kDvlRanges,
  kServo,
  kDepth,
  kLidarH,
  kLidarV,
  kSonar,
  kCamera,
  kOdometry,
  kMapPoses,
  kHull,
  kLandmarks,
  kDropout,
  kGnss,
};

class Rng {
 public:
  Rng(uint64_t seed, Stream stream, uint64_t index = 0)
      : state_(splitmix64(splitmix64(seed) ^ splitmix64(static_cast<uint64_t>(stream) << 32) ^
                          splitmix64(index * 0xD1B54A32D192ED03ULL + 7))) {}

  uint64_t next() {
    state_ += 0x9E3779B97F4A7C15ULL;
    uint64_t z = state_;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  // Uniform in [0, 1).
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  // Standard normal (Box-Muller, both outputs used).
  double gaussian() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    double u1 = uniform();
    while (u1 <= 0.0) u1 = uniform();
    const double u2 = uniform();
    const double radius = std::sqrt(-2.0 * std::log(u1));
    const double angle = 2.0 * M_PI * u2;
    spare_ = radius * std::sin(angle);
    has_spare_ = true;
    return radius * std::cos(angle);
  }

 private:
  uint64_t state_;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

}  // namespace keel::sim
