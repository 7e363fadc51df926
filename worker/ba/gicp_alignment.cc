#include "worker/ba/gicp_alignment.h"

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/registration/gicp.h>

namespace keel::ba {

GicpAlignment align_dvl_returns_to_model(const std::vector<Eigen::Vector3d>& dvl_points_world,
                                         const TriangleMesh& cad_mesh,
                                         const Pose3& T_world_model_guess,
                                         const GicpOptions& options) {
  GicpAlignment out;
  out.T_world_model = T_world_model_guess;
  if (!options.enabled || static_cast<int>(dvl_points_world.size()) < options.min_points) {
    return out;
  }
  // Source: the sparse DVL returns (world); target: the CAD vertices (model). Aligning the
  // sparse cloud onto the dense one gives every return a correspondence; the estimate is
  // T_model_world, inverted below.
  auto source = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  auto target = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  for (const auto& p : dvl_points_world) source->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  for (const auto& v : cad_mesh.vertices) target->push_back(pcl::PointXYZ(v.x(), v.y(), v.z()));
  pcl::GeneralizedIterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ> gicp;
  gicp.setInputSource(source);
  gicp.setInputTarget(target);
  gicp.setMaxCorrespondenceDistance(options.max_correspondence_distance_m);
  gicp.setMaximumIterations(options.max_iterations);
  gicp.setTransformationEpsilon(1e-10);
  gicp.setRotationEpsilon(1e-10);
  gicp.setEuclideanFitnessEpsilon(1e-12);
  pcl::PointCloud<pcl::PointXYZ> aligned;
  const Eigen::Matrix4f guess = T_world_model_guess.inverse().matrix().cast<float>();
  gicp.align(aligned, guess);
  out.ran = true;
  out.converged = gicp.hasConverged();
  out.fitness = gicp.getFitnessScore(options.max_correspondence_distance_m);
  if (out.converged) {
    Pose3 T_model_world = Pose3::Identity();
    T_model_world.matrix() = gicp.getFinalTransformation().cast<double>();
    // Re-orthonormalise the float rotation.
    T_model_world.linear() =
        Eigen::Quaterniond(T_model_world.linear()).normalized().toRotationMatrix();
    out.T_world_model = T_model_world.inverse();
  }
  return out;
}

}  // namespace keel::ba
