// SO(3) helpers on Eigen types: hat, Exp, Log and the right Jacobian (seed 000 ref. [27],
// Forster et al., Sec. III). Rotations are perturbed on the right: R * Exp(delta).
#pragma once

#include <Eigen/Core>

namespace keel::slam {

// (v)^: the skew-symmetric matrix with hat(a) * b = a x b.
Eigen::Matrix3d hat(const Eigen::Vector3d& v);

// Exp: R^3 -> SO(3) (Rodrigues), exact for small angles by Taylor expansion.
Eigen::Matrix3d so3_exp(const Eigen::Vector3d& phi);

// Log: SO(3) -> R^3 with |phi| in [0, pi]; via the quaternion for accuracy near 0 and pi.
Eigen::Vector3d so3_log(const Eigen::Matrix3d& R);

// Right Jacobian J_r(phi): Exp(phi + d) ~= Exp(phi) Exp(J_r(phi) d)   (Forster Eq. (8)).
Eigen::Matrix3d right_jacobian(const Eigen::Vector3d& phi);

// Inverse right Jacobian: Log(Exp(phi) Exp(d)) ~= phi + J_r^{-1}(phi) d   (Forster Eq. (9)).
Eigen::Matrix3d right_jacobian_inverse(const Eigen::Vector3d& phi);

}  // namespace keel::slam
