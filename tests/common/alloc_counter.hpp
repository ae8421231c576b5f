#pragma once
// Counts heap allocations made while a scope is active, by interposing malloc (glibc).
// Exactly one translation unit of a test executable defines HYSIM_DEFINE_ALLOC_HOOKS before
// including this header (that one defines malloc, calloc and realloc).
#include <cstddef>

extern "C" void* __libc_malloc(std::size_t);
extern "C" void* __libc_calloc(std::size_t, std::size_t);
extern "C" void* __libc_realloc(void*, std::size_t);

namespace hysim::testing {
inline thread_local bool g_counting = false;
inline thread_local long g_allocations = 0;

struct AllocationCounter {
  AllocationCounter() { g_allocations = 0; g_counting = true; }
  ~AllocationCounter() { g_counting = false; }
  long count() const { return g_allocations; }
};
}  // namespace hysim::testing

#ifdef HYSIM_DEFINE_ALLOC_HOOKS
extern "C" void* malloc(std::size_t n) {
  if (hysim::testing::g_counting) ++hysim::testing::g_allocations;
  return __libc_malloc(n);
}
extern "C" void* calloc(std::size_t a, std::size_t b) {
  if (hysim::testing::g_counting) ++hysim::testing::g_allocations;
  return __libc_calloc(a, b);
}
extern "C" void* realloc(void* p, std::size_t n) {
  if (hysim::testing::g_counting) ++hysim::testing::g_allocations;
  return __libc_realloc(p, n);
}
#endif  // HYSIM_DEFINE_ALLOC_HOOKS
