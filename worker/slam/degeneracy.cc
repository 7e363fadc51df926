#include "worker/slam/degeneracy.h"

#include <Eigen/Eigenvalues>

#include <algorithm>

namespace keel::slam {

DegeneracyReport analyze_degeneracy(const Matrix6d& information, const DegeneracyOptions& options) {
  DegeneracyReport report;
  const Matrix6d sym = 0.5 * (information + information.transpose());
  Matrix6d projector = Matrix6d::Zero();  // onto the well-observed directions
  for (int block = 0; block < 2; ++block) {
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(sym.block<3, 3>(3 * block, 3 * block));
    const double threshold =
        std::max(block == 0 ? options.min_eigenvalue_translation : options.min_eigenvalue_rotation,
                 options.min_eigenvalue_ratio * es.eigenvalues()(2));
    (block == 0 ? report.eigenvalues_translation : report.eigenvalues_rotation) = es.eigenvalues();
    for (int k = 0; k < 3; ++k) {
      if (es.eigenvalues()[k] < threshold) {
        report.degenerate = true;
      } else {
        const Eigen::Vector3d u = es.eigenvectors().col(k);
        projector.block<3, 3>(3 * block, 3 * block) += u * u.transpose();
      }
    }
  }
  report.well_conditioned_information = projector * sym * projector;
  return report;
}

}  // namespace keel::slam
