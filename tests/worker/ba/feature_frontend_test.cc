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
#include <stdexcept>

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

Eigen::Vector2d project(const PinholeCamera& c, const Pose3& T_world_camera,
                        const Eigen::Vector3d& p_world) {
  const Eigen::Vector3d p = T_world_camera.inverse() * p_world;
  return Eigen::Vector2d(c.fx * p.x() / p.z() + c.cx, c.fy * p.y() / p.z() + c.cy);
}

// Two views 0.3 m apart of points 1.2-2 m away, plus wrong matches that obey the epipolar
// constraint exactly: b's pixel is where a's ray meets b's image at infinity (x_b ~ R x_a), or
// a's ray 40 m out. RANSAC keeps them; the depth check must not.
TEST(FeatureFrontend, MonocularVerificationRejectsMatchesOutOfDepthRange) {
  const PinholeCamera c{500, 500, 320, 240, 640, 480};
  Pose3 T_world_b = Pose3::Identity();
  T_world_b.linear() = Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitY()).toRotationMatrix();
  T_world_b.translation() = Eigen::Vector3d(0.3, 0.02, 0.0);
  const Pose3 T_world_a = Pose3::Identity();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  std::normal_distribution<double> noise(0.0, 0.1);
  std::vector<Eigen::Vector2d> pa, pb;
  for (int i = 0; i < 60; ++i) {
    const Eigen::Vector3d p(0.15 + 0.6 * u(rng), 0.45 * u(rng), 1.6 + 0.4 * u(rng));
    pa.push_back(project(c, T_world_a, p) + Eigen::Vector2d(noise(rng), noise(rng)));
    pb.push_back(project(c, T_world_b, p) + Eigen::Vector2d(noise(rng), noise(rng)));
  }
  const std::vector<Eigen::Vector2d> false_a = {{200, 150}, {400, 300}, {300, 200}};
  const std::vector<double> false_depth_m = {1e9, 1e9, 40.0};
  for (size_t f = 0; f < false_a.size(); ++f) {
    const Eigen::Vector3d ray((false_a[f].x() - c.cx) / c.fx, (false_a[f].y() - c.cy) / c.fy, 1);
    pa.push_back(false_a[f]);
    pb.push_back(project(c, T_world_b, false_depth_m[f] * ray));
  }
  FrontendOptions options;
  options.essential_threshold_px = 0.5;
  const std::vector<bool> gated = verify_monocular_matches(pa, pb, c, 0.3, options);
  int true_kept = 0;
  for (int i = 0; i < 60; ++i) true_kept += gated[i];
  EXPECT_GE(true_kept, 57);
  for (size_t f = 0; f < false_a.size(); ++f) EXPECT_FALSE(gated[60 + f]) << "false match " << f;
  // The epipolar test alone accepts the matches at infinity.
  options.gate_two_view_depth = false;
  const std::vector<bool> epipolar_only = verify_monocular_matches(pa, pb, c, 0.3, options);
  EXPECT_TRUE(epipolar_only[60]);
  EXPECT_TRUE(epipolar_only[61]);
  EXPECT_THROW(verify_monocular_matches(pa, {pb[0]}, c, 0.3, options), std::invalid_argument);
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

// Four cameras 0.2 m apart along x, looking along +z.
std::vector<Pose3> camera_row(int n) {
  std::vector<Pose3> cameras;
  for (int i = 0; i < n; ++i) {
    Pose3 T = Pose3::Identity();
    T.translation() = Eigen::Vector3d(0.2 * i, 0.0, 0.0);
    cameras.push_back(T);
  }
  return cameras;
}

TEST(Triangulation, GateRemovesAnOutlierViewAndUncheckedTwoViewTracks) {
  BaRig rig;
  rig.camera_top = PinholeCamera{600, 600, 320, 240, 640, 480};
  const std::vector<Pose3> cameras = camera_row(4);
  const Eigen::Vector3d point(0.3, -0.1, 1.5);
  FeatureTrack track;
  for (int i = 0; i < 4; ++i)
    track.observations.push_back({i, project(rig.camera_top, cameras[i], point), {}});
  track.observations[2].pixel += Eigen::Vector2d(0, 10);  // a wrong match in view 2
  TriangulationOptions options;                           // min_monocular_views 3
  FeatureTrack four = track;
  EXPECT_TRUE(gate_landmark_observations(point, four, cameras, rig, 3.0, options));
  ASSERT_EQ(four.observations.size(), 3u);
  for (const auto& o : four.observations) EXPECT_NE(o.keyframe, 2);
  // Three views with one wrong: two remain, too few for a monocular landmark.
  FeatureTrack three{0, {track.observations[0], track.observations[1], track.observations[2]}};
  EXPECT_FALSE(gate_landmark_observations(point, three, cameras, rig, 3.0, options));
  EXPECT_EQ(three.observations.size(), 2u);

  // A two-view wrong match displaced along the epipolar line (here the x axis) by 8 px: the
  // triangulated point fits both views, only its depth is wrong, so the reprojection gate
  // passes it and only the view count rejects it.
  FeatureTrack two{0,
                   {{0, project(rig.camera_top, cameras[0], point), {}},
                    {1, project(rig.camera_top, cameras[1], point) + Eigen::Vector2d(8, 0), {}}}};
  TriangulationOptions loose;
  loose.min_parallax_deg = 0;
  const auto wrong = triangulate_track(two, cameras, rig, loose);
  ASSERT_TRUE(wrong);
  EXPECT_GT((*wrong - point).norm(), 0.1);
  for (double e : observation_reprojection_errors_px(*wrong, two, cameras, rig)) EXPECT_LT(e, 1e-6);
  FeatureTrack two_copy = two;
  EXPECT_FALSE(gate_landmark_observations(*wrong, two_copy, cameras, rig, 3.0, options));
  TriangulationOptions two_views = options;
  two_views.min_monocular_views = 2;
  EXPECT_TRUE(gate_landmark_observations(*wrong, two, cameras, rig, 3.0, two_views));

  // A stereo track checks depth by itself: two observations suffice.
  BaRig stereo = rig;
  stereo.camera_bottom = rig.camera_top;
  stereo.T_top_bottom.translation() = Eigen::Vector3d(0, 0.1, 0);
  FeatureTrack pair;
  for (int i = 0; i < 2; ++i) {
    pair.observations.push_back({i, project(rig.camera_top, cameras[i], point),
                                 project(rig.camera_top, cameras[i] * stereo.T_top_bottom, point)});
  }
  EXPECT_TRUE(gate_landmark_observations(point, pair, cameras, stereo, 3.0, options));
}

// The pixel-noise tests: a 600 px camera (and its twin 0.1 m below for stereo), and
// triangulation without gates (they measure the noise, not the geometry).
BaRig sigma_test_rig(bool stereo) {
  BaRig rig;
  rig.camera_top = PinholeCamera{600, 600, 320, 240, 640, 480};
  if (stereo) {
    rig.camera_bottom = rig.camera_top;
    rig.T_top_bottom.translation() = Eigen::Vector3d(0, 0.1, 0);
  }
  return rig;
}

TriangulationOptions without_gates() {
  TriangulationOptions options;
  options.max_reprojection_px = 1e9;
  options.min_parallax_deg = 0;
  return options;
}

// Points seen by 2-4 cameras with 0.5 px Gaussian noise and 2 % wrong observations, each fitted
// by triangulation: the estimate must be the noise, not the (smaller) fitted residual.
TEST(Triangulation, RobustPixelSigmaRecoversTheNoiseOfFittedTracks) {
  const BaRig rig = sigma_test_rig(false);
  const std::vector<Pose3> cameras = camera_row(4);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  std::normal_distribution<double> noise(0.0, 0.5);
  const TriangulationOptions loose = without_gates();
  std::vector<FeatureTrack> tracks;
  std::vector<Eigen::Vector3d> points;
  double raw_sum_sq = 0;
  int raw_n = 0;
  for (int k = 0; k < 600; ++k) {
    const Eigen::Vector3d p(0.3 + 0.5 * u(rng), 0.4 * u(rng), 1.5 + 0.3 * u(rng));
    const int views = 2 + k % 3;
    FeatureTrack t;
    for (int i = 0; i < views; ++i) {
      Eigen::Vector2d px = project(rig.camera_top, cameras[i], p);
      px += (k * 4 + i) % 50 == 0 ? Eigen::Vector2d(30, -20)
                                  : Eigen::Vector2d(noise(rng), noise(rng));
      t.observations.push_back({i, px, {}});
    }
    const auto fitted = triangulate_track(t, cameras, rig, loose);
    if (!fitted) continue;
    for (double e : observation_reprojection_errors_px(*fitted, t, cameras, rig))
      if (e < 5) raw_sum_sq += e * e, ++raw_n;
    tracks.push_back(t);
    points.push_back(*fitted);
  }
  ASSERT_GE(tracks.size(), 550u);
  const double sigma = robust_pixel_sigma_px(points, tracks, cameras, rig);
  EXPECT_NEAR(sigma, 0.5, 0.06);
  // The fitted residuals alone understate the noise: that is what the correction is for.
  EXPECT_LT(std::sqrt(raw_sum_sq / raw_n / 2), 0.4);
  EXPECT_TRUE(std::isinf(robust_pixel_sigma_px({}, {}, cameras, rig)));
}

// Stereo tracks: each camera's image counts once (the larger of the two errors per observation
// would put the estimate ~33 % high).
TEST(Triangulation, RobustPixelSigmaOfStereoTracks) {
  const BaRig rig = sigma_test_rig(true);
  const std::vector<Pose3> cameras = camera_row(3);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  std::normal_distribution<double> noise(0.0, 0.5);
  const TriangulationOptions loose = without_gates();
  std::vector<FeatureTrack> tracks;
  std::vector<Eigen::Vector3d> points;
  for (int k = 0; k < 600; ++k) {
    const Eigen::Vector3d p(0.3 + 0.5 * u(rng), 0.4 * u(rng), 1.5 + 0.3 * u(rng));
    FeatureTrack t;
    for (int i = 0; i < 1 + k % 3; ++i) {
      const Eigen::Vector2d top =
          project(rig.camera_top, cameras[i], p) + Eigen::Vector2d(noise(rng), noise(rng));
      const Eigen::Vector2d bottom = project(rig.camera_top, cameras[i] * rig.T_top_bottom, p) +
                                     Eigen::Vector2d(noise(rng), noise(rng));
      t.observations.push_back({i, top, bottom});
    }
    const auto fitted = triangulate_track(t, cameras, rig, loose);
    if (!fitted) continue;
    tracks.push_back(t);
    points.push_back(*fitted);
  }
  ASSERT_GE(tracks.size(), 550u);
  EXPECT_NEAR(robust_pixel_sigma_px(points, tracks, cameras, rig), 0.5, 0.06);
}

}  // namespace
}  // namespace keel::ba
