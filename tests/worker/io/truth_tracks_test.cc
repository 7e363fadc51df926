#include "worker/io/truth_tracks.h"

#include <gtest/gtest.h>

#include "io_test_util.h"

namespace keel::io {
namespace {

using testing::expect_error;
using testing::TempDir;
using testing::write_text;

TEST(TruthTracks, TruthYamlNamesACsvPerCamera) {
  TempDir dir;
  write_text(dir / "truth.yaml", "keel_truth: 1\nfeature_tracks: {cam0: cam0_tracks.csv}\n");
  EXPECT_EQ(truth_tracks_file(dir / "truth.yaml", "cam0"), dir / "cam0_tracks.csv");
  EXPECT_FALSE(truth_tracks_file(dir / "truth.yaml", "cam1"));
  write_text(dir / "none.yaml", "keel_truth: 1\n");
  EXPECT_FALSE(truth_tracks_file(dir / "none.yaml", "cam0"));
}

TEST(TruthTracks, RowsInTheFilesOrder) {
  TempDir dir;
  write_text(dir / "t.csv", "id,t,u,v\n7,1.5,10.25,20.5\n\n3,1.000000001,0,479\n");
  const std::vector<TruthTrackPixel> rows = read_truth_tracks(dir / "t.csv");
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].landmark_id, 7);
  EXPECT_EQ(rows[0].t_ns, 1500000000);
  EXPECT_EQ(rows[0].pixel, Eigen::Vector2d(10.25, 20.5));
  EXPECT_EQ(rows[1].landmark_id, 3);
  EXPECT_EQ(rows[1].t_ns, 1000000001);
}

TEST(TruthTracks, ErrorsNameFileAndLine) {
  TempDir dir;
  expect_error([&] { read_truth_tracks(dir / "missing.csv"); }, {"missing.csv", "cannot open"});
  write_text(dir / "h.csv", "t,id,u,v\n");
  expect_error([&] { read_truth_tracks(dir / "h.csv"); }, {"h.csv:1", "header id,t,u,v"});
  write_text(dir / "c.csv", "id,t,u,v\n1,2.0,3\n");
  expect_error([&] { read_truth_tracks(dir / "c.csv"); }, {"c.csv:2", "4 columns"});
  write_text(dir / "n.csv", "id,t,u,v\n1,2.0,3,4\n1,2.5,x,4\n");
  expect_error([&] { read_truth_tracks(dir / "n.csv"); }, {"n.csv:3", "expected numbers"});
}

}  // namespace
}  // namespace keel::io
