#pragma once
// std::allocator, except that a value-initialisation (what resize(n) does to new elements)
// leaves them default-initialised: new ints and plain-data structs are not zeroed, for arrays
// that are written in full right after they grow (the node->tet lists' `star`, 4 x #T entries
// per cut; the cut surface's walk tables).
#include <memory>
#include <new>
#include <utility>

namespace hysim::cutting {

template <class T>
struct NoInitAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = NoInitAllocator<U>;
  };
  NoInitAllocator() = default;
  template <class U>
  NoInitAllocator(const NoInitAllocator<U>&) noexcept {}
  template <class U>
  void construct(U* p) noexcept {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

}  // namespace hysim::cutting
