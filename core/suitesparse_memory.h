// SuiteSparse's memory on 64-byte boundaries, so that its factorisations give the same bits
// wherever the allocator puts their workspace.
//
// Ceres factorises with SuiteSparse (CHOLMOD for the sparse solves, SuiteSparseQR for
// ceres::Covariance), which hands its dense fronts to the BLAS. Debian 12's default BLAS
// (ATLAS, libatlas3-base) picks its kernels by the operands' alignment: SuiteSparseQR on the
// same Jacobian gave an R that differed in its last bits, and in how many of its entries are
// exactly zero, when glibc put the fronts in fresh mmap pages (16 bytes past a page) rather
// than on the heap. So the ba stage's x_gM sigma changed with the heap's history (under
// taskset -c 0, with another option). The reference BLAS gives one R in both cases, as does
// ATLAS once every SuiteSparse block is 32- or 64-byte aligned.
#pragma once

namespace keel {

// Points SuiteSparse_config's malloc, calloc and realloc at 64-byte aligned versions (free
// stays std::free). Idempotent and thread-safe; call it before the first Ceres solve. Blocks
// SuiteSparse took before the switch are still released correctly: the aligned ones are
// free()-able, and realloc copies what malloc_usable_size reports.
void use_aligned_suitesparse_memory();

}  // namespace keel
