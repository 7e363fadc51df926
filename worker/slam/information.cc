#include "worker/slam/information.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <stdexcept>

namespace keel::slam {

Eigen::MatrixXd sqrt_information(const Eigen::MatrixXd& information) {
  const Eigen::MatrixXd sym = 0.5 * (information + information.transpose());
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(sym);
  const Eigen::VectorXd root = es.eigenvalues().cwiseMax(0.0).cwiseSqrt();
  return root.asDiagonal() * es.eigenvectors().transpose();
}

Eigen::MatrixXd sqrt_information_from_covariance(const Eigen::MatrixXd& covariance) {
  const Eigen::MatrixXd sym = 0.5 * (covariance + covariance.transpose());
  Eigen::LLT<Eigen::MatrixXd> llt(sym);
  if (llt.info() != Eigen::Success) {
    throw std::invalid_argument("covariance is not positive definite");
  }
  // Sigma = L L^T  =>  Sigma^{-1} = L^{-T} L^{-1}, so S = L^{-1}.
  return llt.matrixL().solve(Eigen::MatrixXd::Identity(sym.rows(), sym.cols()));
}

}  // namespace keel::slam
