#pragma once
// The largest arrays (bond entries, family lists: gigabytes on a 300,000-particle tet case)
// on transparent huge pages. Where a system gives each process 4 KiB pages unless asked
// (transparent_hugepage "madvise", the default of many distributions), every first touch of a
// page is a fault; in the virtual build machine that cost about 3.5 CPU s per GB filled
// against 0.2-2 s per GB on 2 MiB pages (docs/performance-log.md, "Lanczos by default, big
// arrays on huge pages"). The hint changes no value.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>
#if defined(__linux__)
#include <sys/mman.h>
#include <unistd.h>
#endif

namespace breccia {

// Asks for huge pages over the whole pages inside [data, data + bytes); a hint: where the
// system declines, nothing changes.
inline void advise_huge_pages([[maybe_unused]] const void* data, [[maybe_unused]] size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  const auto page = static_cast<uintptr_t>(sysconf(_SC_PAGESIZE));
  const uintptr_t begin = (reinterpret_cast<uintptr_t>(data) + page - 1) & ~(page - 1);
  const uintptr_t end = (reinterpret_cast<uintptr_t>(data) + bytes) & ~(page - 1);
  if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
#endif
}

// v = `count` copies of `value` in fresh storage, the huge-page hint given before the fill
// first touches it.
template <class T>
void assign_on_huge_pages(std::vector<T>& v, size_t count, T value = T{}) {
  std::vector<T>().swap(v);
  v.reserve(count);
  advise_huge_pages(v.data(), count * sizeof(T));
  v.assign(count, value);
}

// Storage that starts as zeros the process has not touched: calloc's (for a block this large
// glibc maps fresh pages, which read as zeros, and writes nothing), and a value-initialisation
// that writes nothing either (construct() without arguments default-initialises: the bytes stay
// calloc's zeros). Reading such pages maps the kernel's shared zero page; only a page written
// later is allocated and cleared. For an array that starts at zero and is mostly never written
// (the softening bonds' damage: 4 B per entry, 0.24 GB on the full concrete case), the set-up
// pays no page clearing for it. Only for trivial types, and only where a vector grows from
// empty or from a copy: a resize that grows back into capacity a shrink left holds the old
// values there, not zeros (bond arrays are sized once).
template <class T>
struct ZeroedAllocator {
  static_assert(std::is_trivially_default_constructible_v<T> && std::is_trivially_destructible_v<T>);
  using value_type = T;
  ZeroedAllocator() = default;
  template <class U>
  ZeroedAllocator(const ZeroedAllocator<U>&) noexcept {}
  T* allocate(size_t count) {
    if (count == 0) return nullptr;
    void* p = std::calloc(count, sizeof(T));
    if (!p) throw std::bad_alloc();
    return static_cast<T*>(p);
  }
  void deallocate(T* p, size_t) noexcept { std::free(p); }
  template <class U>
  void construct(U* p) noexcept {
    ::new (static_cast<void*>(p)) U;  // default-initialised: calloc's zeros stay as they are
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
  template <class U>
  bool operator==(const ZeroedAllocator<U>&) const noexcept {
    return true;
  }
};
template <class T>
using ZeroedVector = std::vector<T, ZeroedAllocator<T>>;

// v = `count` zeros in fresh storage none of whose pages is touched, the huge-page hint given
// first (so a page written later is a huge one, and reads map the huge zero page).
template <class T>
void zeroed_on_huge_pages(ZeroedVector<T>& v, size_t count) {
  ZeroedVector<T>().swap(v);
  v.reserve(count);
  advise_huge_pages(v.data(), count * sizeof(T));
  v.resize(count);  // writes nothing (ZeroedAllocator::construct)
}

// Gives the whole pages of v's storage past its size back to the system (a vector shrunk in
// place, whose tail pages were touched): its elements and capacity stay as they are; a page
// given back reads as zeros if the vector grows into it again.
template <class T>
void release_unused_capacity([[maybe_unused]] std::vector<T>& v) {
#if defined(__linux__) && defined(MADV_DONTNEED)
  const auto page = static_cast<uintptr_t>(sysconf(_SC_PAGESIZE));
  const uintptr_t begin = (reinterpret_cast<uintptr_t>(v.data() + v.size()) + page - 1) & ~(page - 1);
  const uintptr_t end = (reinterpret_cast<uintptr_t>(v.data() + v.capacity())) & ~(page - 1);
  if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_DONTNEED);
#endif
}

}  // namespace breccia
