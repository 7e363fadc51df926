// SuiteSparse's allocations on 64-byte boundaries (suitesparse_memory.h), and blocks from
// before the switch still reallocated and freed correctly.
#include "core/suitesparse_memory.h"

#include <SuiteSparse_config.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdlib>
#include <vector>

namespace keel {
namespace {

bool aligned(const void* p) { return reinterpret_cast<uintptr_t>(p) % 64 == 0; }

TEST(SuiteSparseMemory, EveryBlockIsAlignedAndKeepsItsContents) {
  // A block SuiteSparse took with plain malloc, before the switch.
  double* before = static_cast<double*>(SuiteSparse_malloc(5, sizeof(double)));
  ASSERT_NE(before, nullptr);
  for (int i = 0; i < 5; ++i) before[i] = i + 0.5;
  use_aligned_suitesparse_memory();
  use_aligned_suitesparse_memory();  // idempotent

  std::vector<void*> blocks;
  for (size_t n : {1, 3, 17, 1000, 100000, 3000000}) {  // heap and mmap sizes
    void* p = SuiteSparse_malloc(n, sizeof(double));
    ASSERT_NE(p, nullptr);
    EXPECT_TRUE(aligned(p)) << n;
    blocks.push_back(p);
  }
  const double* zeros = static_cast<double*>(SuiteSparse_calloc(1000, sizeof(double)));
  ASSERT_NE(zeros, nullptr);
  EXPECT_TRUE(aligned(zeros));
  for (int i = 0; i < 1000; ++i) ASSERT_EQ(zeros[i], 0.0);
  SuiteSparse_free(const_cast<double*>(zeros));

  int ok = 0;
  double* grown = static_cast<double*>(SuiteSparse_realloc(100000, 5, sizeof(double), before, &ok));
  ASSERT_EQ(ok, 1);
  EXPECT_TRUE(aligned(grown));
  for (int i = 0; i < 5; ++i) EXPECT_EQ(grown[i], i + 0.5);
  double* shrunk = static_cast<double*>(SuiteSparse_realloc(2, 100000, sizeof(double), grown, &ok));
  ASSERT_EQ(ok, 1);
  EXPECT_TRUE(aligned(shrunk));
  EXPECT_EQ(shrunk[0], 0.5);
  EXPECT_EQ(shrunk[1], 1.5);
  SuiteSparse_free(shrunk);
  for (void* p : blocks) SuiteSparse_free(p);
}

}  // namespace
}  // namespace keel
