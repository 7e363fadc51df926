#include "worker/ba/feature_frontend.h"

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include <Eigen/Geometry>

#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>

#include "worker/ba/rig_geometry.h"
#include "worker/ba/rigid_ransac.h"
#include "worker/ba/track_builder.h"

namespace keel::ba {
namespace {

struct KeyframeFeatures {
  std::vector<Eigen::Vector2d> pixels;         // top image
  std::vector<Eigen::Vector2d> pixels_bottom;  // stereo: matched bottom pixel
  std::vector<Eigen::Vector3d> points_camera;  // stereo: triangulated, top camera frame
  cv::Mat descriptors;                         // one row per feature
};

cv::Mat as_mat(const GrayImage& image) {
  // OpenCV only reads it, so wrapping without a copy is safe.
  return cv::Mat(image.height, image.width, CV_8UC1, const_cast<uint8_t*>(image.pixels.data()));
}

void detect(cv::Ptr<cv::SIFT>& sift, const GrayImage& image, std::vector<cv::KeyPoint>& keypoints,
            cv::Mat& descriptors) {
  sift->detectAndCompute(as_mat(image), cv::noArray(), keypoints, descriptors);
}

// Lowe's ratio test on the two nearest neighbours, then one match per train feature.
std::vector<cv::DMatch> ratio_matches(const cv::Mat& query, const cv::Mat& train, double ratio) {
  if (query.empty() || train.rows < 2) return {};
  cv::BFMatcher matcher(cv::NORM_L2);
  std::vector<std::vector<cv::DMatch>> knn;
  matcher.knnMatch(query, train, knn, 2);
  std::map<int, cv::DMatch> best_per_train;
  for (const auto& m : knn) {
    if (m.size() < 2 || m[0].distance >= ratio * m[1].distance) continue;
    const auto it = best_per_train.find(m[0].trainIdx);
    if (it == best_per_train.end() || m[0].distance < it->second.distance) {
      best_per_train[m[0].trainIdx] = m[0];
    }
  }
  std::vector<cv::DMatch> out;
  for (const auto& [train_index, match] : best_per_train) out.push_back(match);
  return out;
}

Eigen::Vector3d normalised_ray(const PinholeCamera& c, const Eigen::Vector2d& px) {
  return Eigen::Vector3d((px.x() - c.cx) / c.fx, (px.y() - c.cy) / c.fy, 1.0);
}

Eigen::Vector2d project_px(const PinholeCamera& c, const Eigen::Vector3d& p) {
  return Eigen::Vector2d(c.fx * p.x() / p.z() + c.cx, c.fy * p.y() / p.z() + c.cy);
}

// Midpoint of the two rays' closest approach, top camera frame.
Eigen::Vector3d triangulate_stereo(const BaRig& rig, const Eigen::Vector2d& top,
                                   const Eigen::Vector2d& bottom) {
  const Eigen::Vector3d o1 = Eigen::Vector3d::Zero(), d1 = normalised_ray(rig.camera_top, top);
  const Eigen::Vector3d o2 = rig.T_top_bottom.translation();
  const Eigen::Vector3d d2 = rig.T_top_bottom.linear() * normalised_ray(*rig.camera_bottom, bottom);
  Eigen::Matrix2d A;
  A << d1.dot(d1), -d1.dot(d2), d1.dot(d2), -d2.dot(d2);
  const Eigen::Vector2d b((o2 - o1).dot(d1), (o2 - o1).dot(d2));
  const Eigen::Vector2d s = A.colPivHouseholderQr().solve(b);
  return 0.5 * ((o1 + s[0] * d1) + (o2 + s[1] * d2));
}

KeyframeFeatures features_of(const BaKeyframe& keyframe, size_t index, const BaRig& rig,
                             const FrontendOptions& options, cv::Ptr<cv::SIFT>& sift) {
  KeyframeFeatures out;
  if (keyframe.image_top.empty()) return out;
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  detect(sift, keyframe.image_top, keypoints, descriptors);
  if (!rig.camera_bottom) {
    for (const auto& k : keypoints) out.pixels.emplace_back(k.pt.x, k.pt.y);
    out.descriptors = descriptors;
    return out;
  }
  if (keyframe.image_bottom.empty()) {
    throw std::invalid_argument("frontend: keyframes[" + std::to_string(index) +
                                "].image_bottom: expected a bottom image for the stereo rig");
  }
  std::vector<cv::KeyPoint> keypoints_bottom;
  cv::Mat descriptors_bottom;
  detect(sift, keyframe.image_bottom, keypoints_bottom, descriptors_bottom);
  const Pose3 T_bottom_top = rig.T_top_bottom.inverse();
  for (const cv::DMatch& m : ratio_matches(descriptors, descriptors_bottom, options.ratio_test)) {
    const Eigen::Vector2d top(keypoints[m.queryIdx].pt.x, keypoints[m.queryIdx].pt.y);
    const Eigen::Vector2d bottom(keypoints_bottom[m.trainIdx].pt.x,
                                 keypoints_bottom[m.trainIdx].pt.y);
    const Eigen::Vector3d p = triangulate_stereo(rig, top, bottom);
    const Eigen::Vector3d p_bottom = T_bottom_top * p;
    if (p.z() <= 0 || p_bottom.z() <= 0) continue;
    // Rectified stereo: a true match reprojects onto both detections.
    if ((project_px(rig.camera_top, p) - top).norm() > options.stereo_max_reprojection_px ||
        (project_px(*rig.camera_bottom, p_bottom) - bottom).norm() >
            options.stereo_max_reprojection_px) {
      continue;
    }
    out.pixels.push_back(top);
    out.pixels_bottom.push_back(bottom);
    out.points_camera.push_back(p);
    out.descriptors.push_back(descriptors.row(m.queryIdx));
  }
  return out;
}

// Depth of each match in cameras a and b, in metres, from the relative pose (R, t) recovered
// from E (unit baseline) scaled by the initial poses' baseline; NaN where the rays do not meet
// in front of both cameras.
std::vector<std::pair<double, double>> two_view_depths_m(const std::vector<cv::Point2d>& pa,
                                                         const std::vector<cv::Point2d>& pb,
                                                         const cv::Mat& E, const cv::Mat& K,
                                                         double baseline_m, cv::Mat& mask) {
  cv::Mat R, t, points_h;
  // distanceThresh in baselines: far enough to keep every finite depth; cheirality is the test.
  cv::recoverPose(E, pa, pb, K, R, t, 1e6, mask, points_h);
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  std::vector<std::pair<double, double>> depths(pa.size(), {kNaN, kNaN});
  points_h.convertTo(points_h, CV_64F);
  R.convertTo(R, CV_64F);
  t.convertTo(t, CV_64F);
  for (int i = 0; i < points_h.cols; ++i) {
    if (mask.at<uint8_t>(i) == 0) continue;
    const double w = points_h.at<double>(3, i);
    if (std::abs(w) < 1e-12) continue;
    double in_a[3], in_b_z = t.at<double>(2);  // camera b: R x_a + t (t of unit length)
    for (int r = 0; r < 3; ++r) in_a[r] = points_h.at<double>(r, i) / w;
    for (int c = 0; c < 3; ++c) in_b_z += R.at<double>(2, c) * in_a[c];
    depths[i] = {in_a[2] * baseline_m, in_b_z * baseline_m};
  }
  return depths;
}

// The matches' pixels in keyframes a and b, for verify_monocular_matches().
std::vector<bool> verify_essential(const KeyframeFeatures& a, const KeyframeFeatures& b,
                                   const std::vector<cv::DMatch>& matches, const BaRig& rig,
                                   double baseline_m, const FrontendOptions& options) {
  std::vector<Eigen::Vector2d> pa, pb;
  for (const auto& m : matches) {
    pa.push_back(a.pixels[m.queryIdx]);
    pb.push_back(b.pixels[m.trainIdx]);
  }
  return verify_monocular_matches(pa, pb, rig.camera_top, baseline_m, options);
}

// Stereo verification: one rigid motion between the triangulated points.
std::vector<bool> verify_rigid(const KeyframeFeatures& a, const KeyframeFeatures& b,
                               const std::vector<cv::DMatch>& matches,
                               const FrontendOptions& options) {
  std::vector<Eigen::Vector3d> pa, pb;
  for (const auto& m : matches) {
    pa.push_back(a.points_camera[m.queryIdx]);
    pb.push_back(b.points_camera[m.trainIdx]);
  }
  const auto fit =
      rigid_ransac(pa, pb, options.rigid_inlier_threshold_m, options.rigid_ransac_iterations);
  return fit ? fit->inliers : std::vector<bool>(matches.size(), false);
}

}  // namespace

// The epipolar constraint holds for every point at infinity (x_b ~ R x_a satisfies
// x_b^T [t]x R x_a = 0 for any t), so a wrong match with little disparity (repeated hull
// texture, features fixed in the image) passes RANSAC and later triangulates hundreds of metres
// away; the model-free solve then slid one along its ray to 2.5e8 m on keel-sim hauv-hull
// (surface cost 1e19). So an inlier must also triangulate, with E's own pose and the initial
// poses' baseline, in front of both cameras within [min_depth_m, max_depth_m].
std::vector<bool> verify_monocular_matches(const std::vector<Eigen::Vector2d>& pixels_a,
                                           const std::vector<Eigen::Vector2d>& pixels_b,
                                           const PinholeCamera& camera, double baseline_m,
                                           const FrontendOptions& options) {
  if (pixels_a.size() != pixels_b.size())
    throw std::invalid_argument("verify_monocular_matches: pixels_a and pixels_b differ in size");
  std::vector<bool> inliers(pixels_a.size(), false);
  if (pixels_a.size() < 5) return inliers;  // the five-point algorithm's minimum
  std::vector<cv::Point2d> pa, pb;
  for (size_t i = 0; i < pixels_a.size(); ++i) {
    pa.emplace_back(pixels_a[i].x(), pixels_a[i].y());
    pb.emplace_back(pixels_b[i].x(), pixels_b[i].y());
  }
  const cv::Mat K =
      (cv::Mat_<double>(3, 3) << camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);
  cv::Mat mask;
  const cv::Mat E = cv::findEssentialMat(pa, pb, K, cv::RANSAC, options.ransac_confidence,
                                         options.essential_threshold_px, mask);
  // Degenerate configurations return several stacked 3x3 solutions; keep none of them.
  if (E.rows != 3 || E.cols != 3 || mask.empty()) return inliers;
  const bool gate_depth = options.gate_two_view_depth && baseline_m > 0;
  const auto depths = gate_depth ? two_view_depths_m(pa, pb, E, K, baseline_m, mask)
                                 : std::vector<std::pair<double, double>>();
  const auto in_range = [&](double depth_m) {
    return std::isfinite(depth_m) && depth_m >= options.min_depth_m &&
           depth_m <= options.max_depth_m;
  };
  for (size_t i = 0; i < inliers.size(); ++i) {
    inliers[i] = mask.at<uint8_t>(static_cast<int>(i)) != 0;
    if (inliers[i] && gate_depth)  // in front of both cameras, within the range in each
      inliers[i] = in_range(depths[i].first) && in_range(depths[i].second);
  }
  return inliers;
}

FrontendOutput run_frontend(const std::vector<BaKeyframe>& keyframes, const BaRig& rig,
                            const FrontendOptions& options) {
  FrontendOutput out;
  out.stats.ran = true;
  cv::Ptr<cv::SIFT> sift = cv::SIFT::create(options.max_features);
  std::vector<KeyframeFeatures> features;
  std::vector<int> counts;
  for (size_t k = 0; k < keyframes.size(); ++k) {
    features.push_back(features_of(keyframes[k], k, rig, options, sift));
    counts.push_back(static_cast<int>(features.back().pixels.size()));
  }
  const bool stereo = rig.camera_bottom.has_value();
  // Camera centres from the initial poses: the metric scale of the monocular two-view check.
  const ServoMount mount = servo_mount(rig);
  std::vector<Eigen::Vector3d> centres_world;
  for (const BaKeyframe& k : keyframes) {
    centres_world.push_back(
        world_camera_pose(k.T_world_vehicle, k.servo_angle_rad, mount, rig.T_servo_camera)
            .translation());
  }
  std::vector<PairMatches> pairs;
  for (size_t i = 0; i < keyframes.size(); ++i) {
    for (size_t j = i + 1; j < keyframes.size() && j <= i + options.match_window; ++j) {
      const std::vector<cv::DMatch> matches =
          ratio_matches(features[i].descriptors, features[j].descriptors, options.ratio_test);
      if (static_cast<int>(matches.size()) < options.min_inliers) continue;
      ++out.stats.keyframe_pairs_matched;
      const std::vector<bool> inliers =
          stereo ? verify_rigid(features[i], features[j], matches, options)
                 : verify_essential(features[i], features[j], matches, rig,
                                    (centres_world[j] - centres_world[i]).norm(), options);
      PairMatches pair{static_cast<int>(i), static_cast<int>(j), {}};
      for (size_t m = 0; m < matches.size(); ++m) {
        if (inliers[m]) pair.matches.emplace_back(matches[m].queryIdx, matches[m].trainIdx);
      }
      if (static_cast<int>(pair.matches.size()) < options.min_inliers) continue;
      ++out.stats.keyframe_pairs_verified;
      out.stats.verified_matches += static_cast<int>(pair.matches.size());
      pairs.push_back(std::move(pair));
    }
  }
  for (const auto& nodes : build_tracks(pairs, counts)) {
    FeatureTrack track;
    track.landmark_id = static_cast<int64_t>(out.tracks.size());
    for (const TrackNode& n : nodes) {
      FeatureObservation obs;
      obs.keyframe = n.keyframe;
      obs.pixel = features[n.keyframe].pixels[n.feature];
      if (stereo) obs.pixel_bottom = features[n.keyframe].pixels_bottom[n.feature];
      track.observations.push_back(obs);
    }
    out.tracks.push_back(std::move(track));
  }
  out.stats.tracks = static_cast<int>(out.tracks.size());
  return out;
}

}  // namespace keel::ba
