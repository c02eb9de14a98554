// ZeroedVector (huge_pages.hpp): zeros without touching the pages that hold them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <vector>

#include "breccia/common/huge_pages.hpp"

#if defined(__linux__)
#include <sys/mman.h>
#include <unistd.h>
#endif

namespace {

// Zeros where the heap has just handed out other bytes: a block of the same size filled with
// 0xA5 and freed first, so a malloc-backed allocator (or a construct() that wrote nothing on
// memory not zeroed) would likely get it back dirty; calloc's is zero whatever it reuses.
template <class T>
void expect_zeros_after_a_dirty_block(size_t count) {
  {
    std::vector<unsigned char> dirty(count * sizeof(T));
    std::memset(dirty.data(), 0xA5, dirty.size());
  }
  breccia::ZeroedVector<T> v;
  breccia::zeroed_on_huge_pages(v, count);
  ASSERT_EQ(v.size(), count);
  EXPECT_TRUE(std::all_of(v.begin(), v.end(), [](T x) { return x == T{}; })) << count;
  breccia::ZeroedVector<T> grown(count);  // value-initialised from empty: zeros too
  EXPECT_TRUE(std::all_of(grown.begin(), grown.end(), [](T x) { return x == T{}; })) << count;
}

}  // namespace

TEST(ZeroedVector, HoldsZerosWhereTheHeapHeldOtherBytes) {
  expect_zeros_after_a_dirty_block<float>(1000);       // 4 KB: from the heap
  expect_zeros_after_a_dirty_block<uint8_t>(100000);   // 100 KB
  expect_zeros_after_a_dirty_block<float>(16 << 20);   // 64 MB: mapped
}

TEST(ZeroedVector, CopiesAndAssignmentsKeepTheirValues) {
  breccia::ZeroedVector<float> v;
  breccia::zeroed_on_huge_pages(v, 5000);
  v[17] = 0.25f;
  v[4999] = -3.0f;
  const breccia::ZeroedVector<float> copy(v);
  EXPECT_EQ(copy, v);
  const std::vector<float> values = {1.0f, 2.0f, 3.0f};
  breccia::ZeroedVector<float> assigned;
  assigned.assign(values.begin(), values.end());
  EXPECT_EQ(std::vector<float>(assigned.begin(), assigned.end()), values);
  assigned.assign(4, 7.0f);
  EXPECT_EQ(std::vector<float>(assigned.begin(), assigned.end()), std::vector<float>(4, 7.0f));
}

#if defined(__linux__)
// The point of it: sizing the vector touches none of its pages (the first 2 MB, where calloc
// writes its block header, left out), so the process has allocated none of them yet; a
// std::vector of the same size has every page resident after its zero fill.
TEST(ZeroedVector, SizingItTouchesNoPage) {
  const size_t bytes = size_t{64} << 20;
  const long page = sysconf(_SC_PAGESIZE);
  auto resident_pages_past_2mb = [&](const void* data) {
    const uintptr_t begin = (reinterpret_cast<uintptr_t>(data) + (size_t{2} << 20) + page - 1) & ~uintptr_t(page - 1);
    const uintptr_t end = (reinterpret_cast<uintptr_t>(data) + bytes) & ~uintptr_t(page - 1);
    std::vector<unsigned char> in_core((end - begin) / page);
    EXPECT_EQ(mincore(reinterpret_cast<void*>(begin), end - begin, in_core.data()), 0);
    size_t resident = 0;
    for (unsigned char c : in_core) resident += c & 1;
    return std::pair<size_t, size_t>{resident, in_core.size()};
  };
  breccia::ZeroedVector<float> zeroed;
  breccia::zeroed_on_huge_pages(zeroed, bytes / sizeof(float));
  EXPECT_EQ(resident_pages_past_2mb(zeroed.data()).first, 0u);
  std::vector<float> filled(bytes / sizeof(float));  // the check itself can see resident pages
  const auto [resident, pages] = resident_pages_past_2mb(filled.data());
  EXPECT_EQ(resident, pages);
}
#endif
