#include "core/suitesparse_memory.h"

#include <SuiteSparse_config.h>
#include <malloc.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <mutex>

namespace keel {
namespace {

// A cache line: covers the 32-byte alignment ATLAS's kernels look at.
constexpr size_t kAlignment = 64;

void* aligned_malloc(size_t size) {
  void* p = nullptr;
  return posix_memalign(&p, kAlignment, std::max<size_t>(size, 1)) == 0 ? p : nullptr;
}

void* aligned_calloc(size_t count, size_t size) {
  if (size != 0 && count > SIZE_MAX / size) return nullptr;
  void* p = aligned_malloc(count * size);
  if (p != nullptr) std::memset(p, 0, count * size);
  return p;
}

void* aligned_realloc(void* old, size_t size) {
  if (old == nullptr) return aligned_malloc(size);
  void* p = aligned_malloc(size);
  if (p == nullptr) return nullptr;  // `old` stays valid, as with realloc
  std::memcpy(p, old, std::min(malloc_usable_size(old), size));
  std::free(old);
  return p;
}

}  // namespace

void use_aligned_suitesparse_memory() {
  static std::once_flag once;
  std::call_once(once, [] {
    SuiteSparse_config.malloc_func = aligned_malloc;
    SuiteSparse_config.calloc_func = aligned_calloc;
    SuiteSparse_config.realloc_func = aligned_realloc;
    SuiteSparse_config.free_func = std::free;
  });
}

}  // namespace keel
