// Loop closures (`loops.csv`): relative poses T_body_i_body_j between keyframes at t_i, t_j.
#pragma once

#include <filesystem>
#include <vector>

#include "core/pose.h"

namespace keel::io {

struct LoopClosure {
  TimeNs t_i_ns = 0;
  TimeNs t_j_ns = 0;
  Pose3 T_body_i_body_j = Pose3::Identity();
  double sigma_t_m = 0.0;    // translational sigma
  double sigma_r_rad = 0.0;  // rotational sigma
};

// Header `t_i,t_j,x,y,z,qx,qy,qz,qw,sigma_t,sigma_r`. Fails naming file and line on bad
// numbers, |q| off 1 by more than 1e-3, non-positive sigmas or t_i == t_j.
std::vector<LoopClosure> read_loop_closures(const std::filesystem::path& path);
void write_loop_closures(const std::filesystem::path& path, const std::vector<LoopClosure>& loops);

}  // namespace keel::io
