// Piecewise registration: after the global registration, each cubic tile of B gets its own
// rigid correction onto A (compare/tile_correction.h), so a low-frequency distortion between
// two surveys' maps (each map carries its own trajectory's few-centimetre errors, which no
// single rigid transform removes) does not pass for change, while a real change does not pull
// the tile: the correction is estimated from the M3C2 change at coarse core points of B on
// structure stable in both surveys, applied only along the directions that structure
// constrains, and not at all where it is not supported.
// The same stable-structure analysis gives each tile's registration error, the `reg` of
// Lague et al.'s Eq. (1), after the correction (tile_registration_errors).
#pragma once

#include <Eigen/Core>

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "worker/compare/m3c2.h"
#include "worker/compare/tile_correction.h"

namespace keel::compare {

struct LocalRegistrationOptions {
  double tile_m = 10.0;  // side of the cubic tiles of B
  // The registration's core points, one per voxel of B of this side: coarser than the
  // measurement's (a tile holds thousands), their cylinders then independent.
  double core_spacing_m = 0.25;
  // Every this-th point of each cloud takes part: the cores' change needs a few points per
  // cylinder, not the map's density (a quarter of a 2 cm map: ~20 in 0.2 m).
  size_t point_stride = 4;
  M3c2Options m3c2;  // the scales of the cores' change; its core_spacing_m is not used
  TileCorrectionOptions tile;
  int threads = 2;
  std::function<void()> check_canceled;
};

using TileKey = std::array<int64_t, 3>;
TileKey tile_of(const Eigen::Vector3f& p, double tile_m);

struct TileRegistration {
  TileKey key{};
  Eigen::Vector3d center_m = Eigen::Vector3d::Zero();
  TileCorrection correction;
};

struct LocalRegistration {
  std::vector<TileRegistration> tiles;  // tiles of B holding defined core points, key order
  size_t adjusted = 0;                  // tiles whose correction was applied
};

// Moves `moving` (B, already registered globally) in place, tile by tile. The result does not
// depend on the threads.
LocalRegistration register_tiles(const std::vector<Eigen::Vector3f>& reference,
                                 std::vector<Eigen::Vector3f>* moving,
                                 const LocalRegistrationOptions& options);

struct TileError {
  TileKey key{};
  size_t cores = 0, stable = 0;
  double registration_error_m = -1.0;  // -1: too few stable cores, the fallback stands
};

// Each defined core's `reg` (compare/tile_correction.h tile_registration_error) from the cores
// of its tile of side tile_m; cores of a tile with too few stable cores take `fallback_m`.
// `tiles` (optional) receives each tile's figures in key order, `stable` (optional) whether
// each core is on its tile's stable structure.
std::vector<double> tile_registration_errors(const std::vector<CoreChange>& cores, double tile_m,
                                             double fallback_m, double confidence_z,
                                             const TileCorrectionOptions& options, int threads,
                                             std::vector<TileError>* tiles = nullptr,
                                             std::vector<char>* stable = nullptr);

}  // namespace keel::compare
