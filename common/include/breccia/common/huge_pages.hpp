#pragma once
// The largest arrays (bond entries, family lists: gigabytes on a 300,000-particle tet case)
// on transparent huge pages. Where a system gives each process 4 KiB pages unless asked
// (transparent_hugepage "madvise", the default of many distributions), every first touch of a
// page is a fault; in the virtual build machine that cost about 3.5 CPU s per GB filled
// against 0.2-2 s per GB on 2 MiB pages (docs/performance.md). The hint changes no value.
#include <cstddef>
#include <cstdint>
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
