// Piecewise registration: after the global registration, each cubic tile of B is registered
// again onto A (with a margin around it) on stable structure, so a low-frequency distortion
// between two surveys' maps (each map carries its own trajectory's few-centimetre errors, which
// no single rigid transform removes) does not pass for change. A tile keeps its own transform
// only when that is well determined (converged, enough stable pairs, well conditioned) and
// small; otherwise it keeps the global one.
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <vector>

#include "worker/compare/stable_registration.h"

namespace keel::compare {

struct LocalRegistrationOptions {
  double tile_m = 10.0;      // side of the cubic tiles of B
  double margin_m = 1.0;     // A's points this far around a tile take part
  size_t min_points = 2000;  // of B in a tile, to register it
  size_t min_stable_pairs = 100;
  double min_conditioning = 1e-4;  // StableRegistration::conditioning
  double max_translation_m = 0.1;  // larger corrections are not trusted
  double max_rotation_deg = 0.5;
  StableRegistrationOptions registration;
};

struct LocalRegistration {
  size_t tiles = 0;                  // tiles of B with >= min_points
  size_t adjusted = 0;               // tiles that kept their own transform
  std::vector<double> correction_m;  // per adjusted tile, the translation at its centre
};

// Moves `moving` (B, already registered globally) in place, tile by tile; the tiles are
// registered side by side on registration.threads threads (the result does not depend on it).
LocalRegistration register_tiles(const std::vector<Eigen::Vector3f>& reference,
                                 std::vector<Eigen::Vector3f>* moving,
                                 const LocalRegistrationOptions& options);

}  // namespace keel::compare
