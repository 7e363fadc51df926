// Per-vertex deviation of the remeshed model against the brute-force answer: the signed
// distance (Eq. 5, seed 001) to the whole prior mesh.
#include "worker/inspect/vertex_deviation.h"

#include <gtest/gtest.h>

#include <random>

#include "tests/core/mesh_fixtures.h"
#include "core/mesh_query.h"

namespace keel::inspect {
namespace {

TEST(VertexDeviation, MatchesTheSignedDistanceToTheWholePrior) {
  const TriangleMesh prior = keel::testing::make_icosphere(4, 1.0);  // curved, closed
  const keel::MeshQuery whole(prior);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> step(-0.3, 0.3);
  std::bernoulli_distribution pick(0.2);
  TriangleMesh remeshed = prior;
  std::vector<int> counts(prior.vertices.size(), 0);
  for (size_t i = 0; i < prior.vertices.size(); ++i) {
    if (!pick(rng)) continue;
    remeshed.vertices[i] += Eigen::Vector3d(step(rng), step(rng), step(rng));
    counts[i] = 1 + static_cast<int>(i % 3);
  }
  const std::vector<double> deviation = vertex_deviations(prior, remeshed, counts);
  ASSERT_EQ(deviation.size(), prior.vertices.size());
  int inside = 0, outside = 0;
  for (size_t i = 0; i < prior.vertices.size(); ++i) {
    if (counts[i] == 0) {
      EXPECT_EQ(deviation[i], 0.0);
      continue;
    }
    const double expected = whole.signed_distance(remeshed.vertices[i]);
    EXPECT_NEAR(deviation[i], expected, 1e-12) << "vertex " << i;
    // On a unit sphere this is also |v| - 1, up to the facets' sagitta.
    EXPECT_NEAR(deviation[i], remeshed.vertices[i].norm() - 1.0, 0.01);
    (expected < 0 ? inside : outside) += 1;
  }
  EXPECT_GT(inside, 50);
  EXPECT_GT(outside, 50);
}

TEST(VertexDeviation, NothingMovedIsAllZero) {
  const TriangleMesh prior = keel::testing::make_icosphere(2, 1.0);
  const std::vector<double> deviation =
      vertex_deviations(prior, prior, std::vector<int>(prior.vertices.size(), 0));
  EXPECT_EQ(deviation, std::vector<double>(prior.vertices.size(), 0.0));
}

}  // namespace
}  // namespace keel::inspect
