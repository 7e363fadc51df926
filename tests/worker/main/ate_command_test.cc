// `keel-worker ate` / `keel-worker rpe` as programs: evo's published KITTI 00 answer, and TUM
// files and bag topics whose errors have closed forms.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "tests/sim/bag_writer.h"
#include "tests/worker/main/worker_program_fixture.h"
#include "worker/io/tum.h"

namespace {

namespace fs = std::filesystem;

using Output = keel::testing::ProgramOutput;
using keel::testing::read_file;

class TrajectoryToolTest : public keel::testing::WorkerProgramTest {
 protected:
  // A 3D path: a helix with changing heading, 1 pose per second from t0.
  static keel::Trajectory helix(size_t n, double t0_s = 100.0) {
    keel::Trajectory t;
    for (size_t k = 0; k < n; ++k) {
      const double a = 0.3 * static_cast<double>(k);
      keel::StampedPose p;
      p.t_ns = keel::seconds_to_ns(t0_s + static_cast<double>(k));
      p.T_world_body = keel::make_pose(
          Eigen::Quaterniond(Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ())),
          Eigen::Vector3d(5.0 * std::cos(a), 5.0 * std::sin(a), 0.2 * static_cast<double>(k)));
      t.push_back(p);
    }
    return t;
  }

  fs::path write(const std::string& name, const keel::Trajectory& t) {
    const fs::path path = dir_ / name;
    keel::io::write_tum(path, t);
    return path;
  }
};

double json_stat(const std::string& out, const char* key) {
  return nlohmann::json::parse(out)["statistics"][key].get<double>();
}

TEST_F(TrajectoryToolTest, KittiSequence00MatchesEvo) {
  const fs::path data = fs::path(KEEL_SHARED_DIR) / "data";
  if (!fs::exists(data / "KITTI_00_gt.txt")) GTEST_SKIP() << data << ": /work/shared absent";
  const Output o =
      run({"ate", "--ref", (data / "KITTI_00_gt.txt").string(), "--est",
           (data / "KITTI_00_ORB.txt").string(), "--format", "kitti", "--align", "se3"});
  ASSERT_EQ(o.code, 0) << o.err;
  // evo_ape kitti KITTI_00_gt.txt KITTI_00_ORB.txt -a (data/README.md).
  EXPECT_NE(o.out.find("      rmse\t1.303450\n"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("      mean\t1.156997\n"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("    median\t1.065625\n"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("       std\t0.600282\n"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("       min\t0.069313\n"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("       max\t3.587949\n"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("Compared 4541 absolute pose pairs."), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("(with SE(3) Umeyama alignment)"), std::string::npos) << o.out;

  // evo's -a spelling gives the same.
  const Output a = run({"ate", "--ref", (data / "KITTI_00_gt.txt").string(), "--est",
                        (data / "KITTI_00_ORB.txt").string(), "--format", "kitti", "-a", "--json"});
  ASSERT_EQ(a.code, 0) << a.err;
  EXPECT_NEAR(json_stat(a.out, "rmse"), 1.3034497, 5e-7);
}

TEST_F(TrajectoryToolTest, ConstantOffsetGivesItsLengthWithoutAlignmentAndZeroWithIt) {
  const keel::Trajectory ref = helix(40);
  keel::Trajectory est = ref;
  const Eigen::Vector3d offset(1.0, 2.0, 2.0);  // |offset| = 3
  for (auto& p : est) p.T_world_body.translation() += offset;
  const std::string r = write("ref.tum", ref).string(), e = write("est.tum", est).string();

  const Output none = run({"ate", "--ref", r, "--est", e, "--json"});
  ASSERT_EQ(none.code, 0) << none.err;
  EXPECT_NEAR(json_stat(none.out, "rmse"), 3.0, 1e-9);
  EXPECT_NEAR(json_stat(none.out, "std"), 0.0, 1e-9);
  EXPECT_EQ(nlohmann::json::parse(none.out)["pairs"], 40);

  const Output se3 = run({"ate", "--ref", r, "--est", e, "--align", "se3", "--json"});
  ASSERT_EQ(se3.code, 0) << se3.err;
  EXPECT_NEAR(json_stat(se3.out, "rmse"), 0.0, 1e-6);

  // A pure translation changes no relative pose: RPE is 0 whatever the alignment.
  const Output rpe = run({"rpe", "--ref", r, "--est", e, "--delta", "2", "--json"});
  ASSERT_EQ(rpe.code, 0) << rpe.err;
  EXPECT_NEAR(json_stat(rpe.out, "max"), 0.0, 1e-9);
  EXPECT_EQ(nlohmann::json::parse(rpe.out)["pairs"], 19);  // (0,2), (2,4), ... (36,38)
}

TEST_F(TrajectoryToolTest, ScaledEstimateNeedsSim3AndRotationErrorIsItsAngle) {
  const keel::Trajectory ref = helix(30);
  keel::Trajectory scaled = ref, rotated = ref;
  for (auto& p : scaled) p.T_world_body.translation() *= 1.5;
  // Every estimated orientation off by 2 degrees about its own x axis: angle_deg is 2.
  for (auto& p : rotated)
    p.T_world_body.linear() =
        p.T_world_body.linear() *
        Eigen::AngleAxisd(2.0 * M_PI / 180.0, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const std::string r = write("ref.tum", ref).string();
  const std::string s = write("scaled.tum", scaled).string();
  const std::string q = write("rotated.tum", rotated).string();

  const Output sim3 = run({"ate", "--ref", r, "--est", s, "-a", "-s", "--json"});
  ASSERT_EQ(sim3.code, 0) << sim3.err;
  EXPECT_NEAR(json_stat(sim3.out, "rmse"), 0.0, 1e-6);
  EXPECT_NEAR(nlohmann::json::parse(sim3.out)["alignment_transform"]["scale"].get<double>(),
              1.0 / 1.5, 1e-9);
  const Output se3 = run({"ate", "--ref", r, "--est", s, "--align", "se3", "--json"});
  EXPECT_GT(json_stat(se3.out, "rmse"), 0.5);

  const Output angle =
      run({"ate", "--ref", r, "--est", q, "--pose-relation", "angle_deg", "--json"});
  ASSERT_EQ(angle.code, 0) << angle.err;
  EXPECT_NEAR(json_stat(angle.out, "min"), 2.0, 1e-6);
  EXPECT_NEAR(json_stat(angle.out, "max"), 2.0, 1e-6);
  const Output text = run({"rpe", "--ref", r, "--est", q, "--pose-relation", "angle_deg"});
  ASSERT_EQ(text.code, 0) << text.err;
  // Body-frame rotation offsets cancel in relative poses only when they commute; here they are
  // about x while the path turns about z, so RPE angle is non-zero but bounded by 2 x 2 deg.
  EXPECT_NE(text.out.find("RPE w.r.t. rotation angle in degrees (deg)\nfor delta = 1 (frames)"),
            std::string::npos)
      << text.out;
}

TEST_F(TrajectoryToolTest, TimeOffsetAndToleranceControlAssociation) {
  const keel::Trajectory ref = helix(20);
  keel::Trajectory late = ref;
  for (auto& p : late) p.t_ns += 500000000;  // 0.5 s later
  const std::string r = write("ref.tum", ref).string(), e = write("late.tum", late).string();
  const Output none = run({"ate", "--ref", r, "--est", e});
  EXPECT_EQ(none.code, 1);
  EXPECT_NE(none.err.find("no matching timestamps"), std::string::npos) << none.err;
  const Output shifted = run({"ate", "--ref", r, "--est", e, "--t-offset", "-0.5", "--json"});
  ASSERT_EQ(shifted.code, 0) << shifted.err;
  EXPECT_EQ(nlohmann::json::parse(shifted.out)["pairs"], 20);
  EXPECT_NEAR(json_stat(shifted.out, "rmse"), 0.0, 1e-9);
  const Output loose = run({"ate", "--ref", r, "--est", e, "--t-max-diff", "0.6", "--json"});
  ASSERT_EQ(loose.code, 0) << loose.err;
  EXPECT_EQ(nlohmann::json::parse(loose.out)["pairs"], 20);
}

TEST_F(TrajectoryToolTest, ReadsBagTopics) {
  const keel::Trajectory ref = helix(25);
  keel::Trajectory est = ref;
  for (auto& p : est) p.T_world_body.translation().z() += 0.25;
  const fs::path bag = dir_ / "run.bag";
  {
    keel::sim::BagWriter writer(bag.string());
    for (const auto& p : ref) writer.pose("/truth", "world", p);
    for (const auto& p : est) writer.odometry("/odom", "world", "base_link", p);
    writer.close();
  }
  const Output o =
      run({"ate", "--ref", bag.string() + ":/truth", "--est", bag.string() + ":/odom", "--json"});
  ASSERT_EQ(o.code, 0) << o.err;
  EXPECT_NEAR(json_stat(o.out, "rmse"), 0.25, 1e-6);
  const Output missing =
      run({"ate", "--ref", bag.string() + ":/nope", "--est", bag.string() + ":/odom"});
  EXPECT_EQ(missing.code, 1);
  EXPECT_NE(missing.err.find("/nope"), std::string::npos) << missing.err;
}

TEST_F(TrajectoryToolTest, BadInputNamesTheFileAndLine) {
  const fs::path bad = dir_ / "bad.kitti";
  std::ofstream(bad) << "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1\n";
  const Output o = run({"ate", "--ref", bad.string(), "--est", bad.string(), "--format", "kitti"});
  EXPECT_EQ(o.code, 1);
  EXPECT_NE(o.err.find("bad.kitti:2"), std::string::npos) << o.err;
  EXPECT_NE(o.err.find("expected 12 values"), std::string::npos) << o.err;
  const Output align = run({"ate", "--ref", bad.string(), "--est", bad.string(), "--align", "se2"});
  EXPECT_EQ(align.code, 1);
  EXPECT_NE(align.err.find("--align se2"), std::string::npos) << align.err;
  const Output nofile = run({"ate", "--ref", (dir_ / "none.tum").string(), "--est", bad.string()});
  EXPECT_EQ(nofile.code, 1);
  EXPECT_NE(nofile.err.find("none.tum"), std::string::npos) << nofile.err;
}

}  // namespace
