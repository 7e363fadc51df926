#include "worker/slam/gicp_odometry.h"

#include <pcl/filters/voxel_grid.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/registration/gicp.h>

#include <Eigen/Eigenvalues>

#include <stdexcept>
#include <string>

#include "worker/slam/so3.h"

namespace keel::slam {
namespace {

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

// Sensor-frame scan -> downsampled body-frame PCL cloud.
Cloud::Ptr to_body_cloud(const PointCloud& scan, const Pose3& T_body_sensor, double leaf_m) {
  Cloud::Ptr raw(new Cloud);
  raw->reserve(scan.size());
  for (const Eigen::Vector3f& p : scan.xyz) {
    if (!p.allFinite()) continue;
    const Eigen::Vector3d q = T_body_sensor * p.cast<double>();
    raw->push_back(pcl::PointXYZ(static_cast<float>(q.x()), static_cast<float>(q.y()),
                                 static_cast<float>(q.z())));
  }
  if (leaf_m <= 0.0) return raw;
  Cloud::Ptr out(new Cloud);
  pcl::VoxelGrid<pcl::PointXYZ> grid;
  grid.setLeafSize(static_cast<float>(leaf_m), static_cast<float>(leaf_m),
                   static_cast<float>(leaf_m));
  grid.setInputCloud(raw);
  grid.filter(*out);
  return out;
}

Cloud::Ptr to_cloud(const PointCloud& scan) {
  Cloud::Ptr c(new Cloud);
  for (const Eigen::Vector3f& p : scan.xyz) c->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  return c;
}

// Point-to-plane Hessian of the residuals n^T (R s + t - q) at the converged pose, tangent
// [delta t, delta phi] with R <- R Exp(delta phi) (Zhang et al. ICRA 2016 analyse exactly this
// matrix for degeneracy).
Matrix6d information_of(const Cloud::Ptr& target, const Cloud::Ptr& source, const Pose3& T,
                        const GicpOdometryOptions& o) {
  pcl::KdTreeFLANN<pcl::PointXYZ> tree;
  tree.setInputCloud(target);
  Matrix6d H = Matrix6d::Zero();
  std::vector<int> idx;
  std::vector<float> d2;
  const double max_d2 = o.max_correspondence_m * o.max_correspondence_m;
  for (const pcl::PointXYZ& ps : source->points) {
    const Eigen::Vector3d s(ps.x, ps.y, ps.z);
    const Eigen::Vector3d q = T * s;
    const pcl::PointXYZ pq(static_cast<float>(q.x()), static_cast<float>(q.y()),
                           static_cast<float>(q.z()));
    if (tree.nearestKSearch(pq, o.normal_neighbors, idx, d2) < o.normal_neighbors) continue;
    if (d2[0] > max_d2) continue;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (int i : idx) mean += target->points[i].getVector3fMap().cast<double>();
    mean /= static_cast<double>(idx.size());
    Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
    for (int i : idx) {
      const Eigen::Vector3d e = target->points[i].getVector3fMap().cast<double>() - mean;
      C += e * e.transpose();
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C);
    const double sum = es.eigenvalues().sum();
    if (sum <= 0.0 || es.eigenvalues()(0) / sum > o.max_planarity_ratio) continue;
    const Eigen::Vector3d n = es.eigenvectors().col(0);
    Eigen::Matrix<double, 1, 6> J;
    J.head<3>() = n.transpose();
    J.tail<3>() = -n.transpose() * T.linear() * hat(s);
    H += J.transpose() * J;
  }
  return H / (o.point_sigma_m * o.point_sigma_m);
}

bool near_guess(const Pose3& T, const Pose3& guess, const GicpOdometryOptions& o) {
  const Pose3 d = guess.inverse() * T;
  const bool t_ok = o.max_translation_from_guess_m <= 0.0 ||
                    d.translation().norm() <= o.max_translation_from_guess_m;
  const bool r_ok = o.max_rotation_from_guess_rad <= 0.0 ||
                    so3_log(d.linear()).norm() <= o.max_rotation_from_guess_rad;
  return t_ok && r_ok;
}

}  // namespace

Matrix6d point_to_plane_information(const PointCloud& target, const PointCloud& source,
                                    const Pose3& T_target_source,
                                    const GicpOdometryOptions& options) {
  return information_of(to_cloud(target), to_cloud(source), T_target_source, options);
}

std::vector<RelativePoseMeasurement> relative_poses_from_scans(
    const std::vector<PointCloud>& scans, const Pose3& T_body_sensor,
    const std::vector<Pose3>& initial_T_world_body, const GicpOdometryOptions& options) {
  if (scans.size() != initial_T_world_body.size()) {
    throw std::invalid_argument("gicp odometry: " + std::to_string(scans.size()) + " scans but " +
                                std::to_string(initial_T_world_body.size()) +
                                " initial poses; expected one per keyframe");
  }
  std::vector<Cloud::Ptr> clouds;
  for (size_t k = 0; k < scans.size(); ++k) {
    if (k > 0 && scans[k].t_ns <= scans[k - 1].t_ns) {
      throw std::invalid_argument("gicp odometry: scan " + std::to_string(k) +
                                  " is not stamped after the previous one");
    }
    clouds.push_back(to_body_cloud(scans[k], T_body_sensor, options.voxel_leaf_m));
    if (clouds.back()->size() < static_cast<size_t>(options.normal_neighbors)) {
      throw std::invalid_argument("gicp odometry: scan " + std::to_string(k) + " has " +
                                  std::to_string(clouds.back()->size()) +
                                  " points after downsampling; too few to match");
    }
  }
  std::vector<RelativePoseMeasurement> edges;
  for (size_t k = 1; k < scans.size(); ++k) {
    pcl::GeneralizedIterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ> gicp;
    gicp.setMaximumIterations(options.max_iterations);
    gicp.setMaxCorrespondenceDistance(options.max_correspondence_m);
    gicp.setTransformationEpsilon(options.transformation_epsilon);
    gicp.setInputTarget(clouds[k - 1]);
    gicp.setInputSource(clouds[k]);
    const Pose3 guess = initial_T_world_body[k - 1].inverse() * initial_T_world_body[k];
    Cloud aligned;
    gicp.align(aligned, guess.matrix().cast<float>());
    RelativePoseMeasurement m;
    m.t_i_ns = scans[k - 1].t_ns;
    m.t_j_ns = scans[k].t_ns;
    Pose3 T = guess;
    if (gicp.hasConverged()) {
      T.matrix() = gicp.getFinalTransformation().cast<double>();
      // Re-orthonormalise the float result.
      T.linear() = Eigen::Quaterniond(T.linear()).normalized().toRotationMatrix();
    }
    if (gicp.hasConverged() && near_guess(T, guess, options)) {
      m.T_i_j = T;
      m.information = information_of(clouds[k - 1], clouds[k], m.T_i_j, options);
    } else {
      m.T_i_j = guess;  // no information: the solver sees a fully degenerate edge
      m.information.setZero();
    }
    edges.push_back(m);
  }
  return edges;
}

}  // namespace keel::slam
