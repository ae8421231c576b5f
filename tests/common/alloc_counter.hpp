#pragma once
// Counts heap allocations made while a scope is active. Exactly one translation unit of a test
// executable defines HYSIM_DEFINE_ALLOC_HOOKS before including this header (that one installs
// the hooks). Plain builds interpose malloc, calloc and realloc (glibc); under AddressSanitizer
// or ThreadSanitizer, which own malloc, the sanitizer's allocator hooks count instead, so the
// "allocates nothing" tests keep counting there (Eigen allocates through malloc, not new).
#include <cstddef>

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define HYSIM_ALLOC_COUNT_BY_SANITIZER 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define HYSIM_ALLOC_COUNT_BY_SANITIZER 1
#endif
#endif

#ifdef HYSIM_ALLOC_COUNT_BY_SANITIZER
// The sanitizers' public allocator interface (sanitizer/allocator_interface.h, which GCC's
// packages do not ship): hooks called on every allocation and free.
extern "C" int __sanitizer_install_malloc_and_free_hooks(void (*malloc_hook)(const volatile void*, std::size_t),
                                                         void (*free_hook)(const volatile void*));
#else
extern "C" void* __libc_malloc(std::size_t);
extern "C" void* __libc_calloc(std::size_t, std::size_t);
extern "C" void* __libc_realloc(void*, std::size_t);
#endif

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
#ifdef HYSIM_ALLOC_COUNT_BY_SANITIZER
namespace hysim::testing {
inline void countAllocation(const volatile void*, std::size_t) {
  if (g_counting) ++g_allocations;
}
inline void ignoreFree(const volatile void*) {}
// Installed before main, once per executable.
inline const int g_hooks_installed = __sanitizer_install_malloc_and_free_hooks(countAllocation, ignoreFree);
}  // namespace hysim::testing
#else
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
#endif  // HYSIM_ALLOC_COUNT_BY_SANITIZER
#endif  // HYSIM_DEFINE_ALLOC_HOOKS
