// Frontend of Sec. 2.7, seed 001, on rendered images of a textured hull plate: every track it
// builds must be one 3D point (triangulated with the true camera poses it lies on the plate
// and reprojects onto all its detections). Also rigid RANSAC, track building and
// triangulation against known answers.
#include "worker/ba/feature_frontend.h"

#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <Eigen/Geometry>

#include <cmath>
#include <cstdio>
#include <random>

#include "worker/ba/model_assisted_ba.h"
#include "worker/ba/rigid_ransac.h"
#include "worker/ba/track_builder.h"
#include "worker/ba/triangulation.h"

namespace keel::ba {
namespace {

constexpr double kPlateZ = 1.5;          // the plate is the plane z = 1.5 m (world)
constexpr double kTextureHalf = 2.0;     // covering x, y in +-2 m
constexpr double kTexturePixel = 0.002;  // 2 mm texels

// Blobby random texture at several scales: plenty of SIFT keypoints.
cv::Mat make_texture(uint32_t seed) {
  const int n = static_cast<int>(2 * kTextureHalf / kTexturePixel);
  cv::RNG rng(seed);
  cv::Mat sum = cv::Mat::zeros(n, n, CV_32F);
  for (double sigma : {2.0, 5.0, 12.0}) {
    cv::Mat noise(n, n, CV_32F);
    rng.fill(noise, cv::RNG::UNIFORM, 0.0, 1.0);
    cv::GaussianBlur(noise, noise, cv::Size(0, 0), sigma);
    cv::normalize(noise, noise, 0, 1, cv::NORM_MINMAX);
    sum += noise;
  }
  cv::Mat texture;
  cv::normalize(sum, sum, 0, 255, cv::NORM_MINMAX);
  sum.convertTo(texture, CV_8U);
  return texture;
}

// The plate seen by a camera at T_world_camera (looking up at it).
GrayImage render(const cv::Mat& texture, const PinholeCamera& c, const Pose3& T_world_camera) {
  cv::Mat map_x(c.height, c.width, CV_32F), map_y(c.height, c.width, CV_32F);
  for (int v = 0; v < c.height; ++v) {
    for (int u = 0; u < c.width; ++u) {
      const Eigen::Vector3d d =
          T_world_camera.linear() * Eigen::Vector3d((u - c.cx) / c.fx, (v - c.cy) / c.fy, 1.0);
      const Eigen::Vector3d o = T_world_camera.translation();
      const Eigen::Vector3d p = o + (kPlateZ - o.z()) / d.z() * d;
      map_x.at<float>(v, u) = static_cast<float>((p.x() + kTextureHalf) / kTexturePixel);
      map_y.at<float>(v, u) = static_cast<float>((p.y() + kTextureHalf) / kTexturePixel);
    }
  }
  cv::Mat image;
  cv::remap(texture, image, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REFLECT);
  GrayImage out{c.width, c.height, {}};
  out.pixels.assign(image.data, image.data + image.total());
  return out;
}

struct RenderedSurvey {
  BaRig rig;
  std::vector<BaKeyframe> keyframes;
  std::vector<Pose3> T_world_camera;
};

RenderedSurvey render_survey(bool stereo) {
  RenderedSurvey s;
  s.rig.camera_top = PinholeCamera{500, 500, 320, 240, 640, 480};
  if (stereo) {
    s.rig.camera_bottom = s.rig.camera_top;
    s.rig.T_top_bottom.translation() = Eigen::Vector3d(0, 0.1, 0);
  }
  const cv::Mat texture = make_texture(5);
  for (int i = 0; i < 6; ++i) {
    Pose3 T = Pose3::Identity();
    T.linear() = (Eigen::AngleAxisd(0.03 * i, Eigen::Vector3d::UnitZ()) *
                  Eigen::AngleAxisd(0.02 * (i % 2), Eigen::Vector3d::UnitX()))
                     .toRotationMatrix();
    T.translation() = Eigen::Vector3d(0.12 * i, 0.02 * i, 0.01 * (i % 3));
    BaKeyframe k;
    k.t_ns = (i + 1) * 1'000'000'000LL;
    k.image_top = render(texture, s.rig.camera_top, T);
    if (stereo) k.image_bottom = render(texture, *s.rig.camera_bottom, T * s.rig.T_top_bottom);
    s.keyframes.push_back(std::move(k));
    s.T_world_camera.push_back(T);
  }
  return s;
}

void expect_tracks_are_plate_points(bool stereo) {
  const RenderedSurvey s = render_survey(stereo);
  const FrontendOutput out = run_frontend(s.keyframes, s.rig, FrontendOptions{});
  std::printf("pairs matched %d verified %d, matches %d, tracks %d\n",
              out.stats.keyframe_pairs_matched, out.stats.keyframe_pairs_verified,
              out.stats.verified_matches, out.stats.tracks);
  ASSERT_GE(out.tracks.size(), 100u);
  TriangulationOptions gates;
  gates.max_reprojection_px = 1e9;  // judge the points here, not in the triangulation
  gates.min_parallax_deg = 0;
  int good = 0, observations = 0;
  for (const FeatureTrack& t : out.tracks) {
    observations += static_cast<int>(t.observations.size());
    for (const auto& o : t.observations) EXPECT_EQ(o.pixel_bottom.has_value(), stereo);
    const auto p = triangulate_track(t, s.T_world_camera, s.rig, gates);
    if (!p) continue;
    double worst_px = 0;
    for (const auto& o : t.observations) {
      const Eigen::Vector3d c = s.T_world_camera[o.keyframe].inverse() * *p;
      const Eigen::Vector2d uv(500 * c.x() / c.z() + 320, 500 * c.y() / c.z() + 240);
      worst_px = std::max(worst_px, (uv - o.pixel).norm());
    }
    good += std::abs(p->z() - kPlateZ) < 0.01 && worst_px < 2.0;
  }
  const double fraction = double(good) / out.tracks.size();
  std::printf("%s: %zu tracks, %.2f observations per track, %.3f on the plate\n",
              stereo ? "stereo" : "mono", out.tracks.size(),
              double(observations) / out.tracks.size(), fraction);
  EXPECT_GE(fraction, 0.97);
  EXPECT_GE(double(observations) / out.tracks.size(), 2.5);  // tracks span several keyframes
}

TEST(FeatureFrontend, MonocularTracksAreConsistentPlatePoints) {
  expect_tracks_are_plate_points(false);
}

TEST(FeatureFrontend, StereoTracksAreConsistentPlatePoints) {
  expect_tracks_are_plate_points(true);
}

TEST(FeatureFrontend, StereoWithoutBottomImageNamesTheKeyframe) {
  RenderedSurvey s = render_survey(true);
  s.keyframes[2].image_bottom = GrayImage{};
  try {
    run_frontend(s.keyframes, s.rig, FrontendOptions{});
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("keyframes[2].image_bottom"), std::string::npos);
  }
}

// The whole pipeline from images: frontend, triangulation, GICP, the three modes, with the
// plate as the CAD (vehicle = servo = camera frames, the DVL at the camera looking up).
TEST(FeatureFrontend, ImagesRunThroughTheWholePipeline) {
  const RenderedSurvey s = render_survey(false);
  BaProblem problem;
  problem.rig = s.rig;
  problem.keyframes = s.keyframes;
  for (size_t i = 0; i < s.keyframes.size(); ++i) {
    problem.keyframes[i].T_world_vehicle = s.T_world_camera[i];
    for (int b = 0; b < 4; ++b) {
      const double az = M_PI / 4 + b * M_PI / 2;
      const Eigen::Vector3d d(0.5 * std::cos(az), 0.5 * std::sin(az), std::sqrt(0.75));
      const Eigen::Vector3d d_world = s.T_world_camera[i].linear() * d;
      const double range = (kPlateZ - s.T_world_camera[i].translation().z()) / d_world.z();
      problem.dvl_ranges.push_back({static_cast<int>(i), b, d, range});
    }
  }
  problem.odometry = odometry_from_initial_poses(problem.keyframes);
  // The plate, normals down to the cameras.
  problem.cad_mesh.vertices = {
      {-3, -3, kPlateZ}, {3, -3, kPlateZ}, {3, 3, kPlateZ}, {-3, 3, kPlateZ}};
  problem.cad_mesh.faces = {{0, 2, 1}, {0, 3, 2}};
  for (int x = -30; x <= 30; ++x) {  // dense vertices for GICP's target cloud
    for (int y = -30; y <= 30; ++y)
      problem.cad_mesh.vertices.emplace_back(0.1 * x, 0.1 * y, kPlateZ);
  }
  BaOptions options;
  options.gicp.min_points = 10;
  const BaResult result = run_model_assisted_ba(problem, options);
  EXPECT_TRUE(result.frontend.ran);
  EXPECT_GE(result.landmarks_triangulated, 100);
  const BaModeResult* proposed = result.find(BaMode::kProposed);
  ASSERT_NE(proposed, nullptr);
  int on_plate = 0;
  for (const BaLandmark& l : proposed->landmarks)
    on_plate += std::abs(l.signed_distance_m) < 0.01 && l.lambda == 1;
  EXPECT_GE(on_plate, 0.95 * proposed->landmarks.size());
  // Algorithm 1's input: landmarks seen from keyframe 0, in its camera frame, 1.5 m ahead.
  const auto in_camera = landmarks_in_camera(*proposed, 0);
  ASSERT_FALSE(in_camera.empty());
  for (const auto& p : in_camera) EXPECT_NEAR(p.point_camera.z(), kPlateZ, 0.02);
}

TEST(RigidRansac, RecoversMotionDespiteOutliers) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1, 1);
  Pose3 T = Pose3::Identity();
  T.linear() = Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(0.3, -0.2, 0.5);
  std::vector<Eigen::Vector3d> a, b;
  std::vector<bool> truth;
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d p(u(rng), u(rng), 1.5 + 0.2 * u(rng));
    const bool outlier = i % 3 == 0;  // a third are wrong matches
    b.push_back(p);
    a.push_back(outlier ? Eigen::Vector3d(u(rng), u(rng), 1.5 + u(rng))
                        : T * p + 0.002 * Eigen::Vector3d(u(rng), u(rng), u(rng)));
    truth.push_back(!outlier);
  }
  const auto fit = rigid_ransac(a, b, 0.02, 300);
  ASSERT_TRUE(fit);
  EXPECT_LT((fit->T_a_b.matrix() - T.matrix()).norm(), 0.01);
  int agree = 0;
  for (size_t i = 0; i < a.size(); ++i) agree += fit->inliers[i] == truth[i];
  EXPECT_GE(agree, 197);  // an outlier may fall within 2 cm by chance
  EXPECT_FALSE(rigid_ransac({a[0], a[1]}, {b[0], b[1]}, 0.02, 10));
}

TEST(TrackBuilder, ChainsMatchesAndDropsConflicts) {
  // 0:0 - 1:0 - 2:0 a track of three; 0:1 - 1:1 - 2:1 and 1:1 - 2:2 conflict (two features of
  // keyframe 2); 0:2 alone.
  std::vector<PairMatches> pairs = {{0, 1, {{0, 0}, {1, 1}}}, {1, 2, {{0, 0}, {1, 1}, {1, 2}}}};
  const auto tracks = build_tracks(pairs, {3, 2, 3});
  ASSERT_EQ(tracks.size(), 1u);
  ASSERT_EQ(tracks[0].size(), 3u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(tracks[0][k].keyframe, k);
    EXPECT_EQ(tracks[0][k].feature, 0);
  }
  EXPECT_THROW(build_tracks({{0, 1, {{5, 0}}}}, {3, 3}), std::out_of_range);
}

TEST(Triangulation, ExactObservationsGiveThePoint) {
  BaRig rig;
  rig.camera_top = PinholeCamera{600, 600, 320, 240, 640, 480};
  const Eigen::Vector3d point(0.3, -0.2, 1.6);
  std::vector<Pose3> cameras;
  FeatureTrack track;
  for (int i = 0; i < 3; ++i) {
    Pose3 T = Pose3::Identity();
    T.linear() = Eigen::AngleAxisd(0.05 * i, Eigen::Vector3d::UnitY()).toRotationMatrix();
    T.translation() = Eigen::Vector3d(0.25 * i, 0.0, 0.0);
    cameras.push_back(T);
    const Eigen::Vector3d c = T.inverse() * point;
    track.observations.push_back(
        {i, Eigen::Vector2d(600 * c.x() / c.z() + 320, 600 * c.y() / c.z() + 240), {}});
  }
  const auto p = triangulate_track(track, cameras, rig, TriangulationOptions{});
  ASSERT_TRUE(p);
  EXPECT_LT((*p - point).norm(), 1e-9);
  // One ray is not a point; a point behind the cameras is rejected.
  FeatureTrack single{0, {track.observations[0]}};
  EXPECT_FALSE(triangulate_track(single, cameras, rig, TriangulationOptions{}));
  TriangulationOptions close;
  close.min_depth_m = 2.0;
  EXPECT_FALSE(triangulate_track(track, cameras, rig, close));
}

}  // namespace
}  // namespace keel::ba
