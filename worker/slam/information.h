// Square-root information matrices for whitening residuals: ||S r||^2 = r^T Sigma^{-1} r.
#pragma once

#include <Eigen/Core>

namespace keel::slam {

// S with S^T S = information, for symmetric positive semi-definite information (directions
// with non-positive eigenvalues get zero rows, so they carry no information).
Eigen::MatrixXd sqrt_information(const Eigen::MatrixXd& information);

// S with S^T S = covariance^{-1}. Throws std::invalid_argument when covariance is not
// positive definite.
Eigen::MatrixXd sqrt_information_from_covariance(const Eigen::MatrixXd& covariance);

}  // namespace keel::slam
