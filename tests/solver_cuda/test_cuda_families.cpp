// The bond families built on the GPU (cuda_families.cu) against build_families: the same
// offsets and partners, bit for bit, on a lattice and on a cloud graded over several reach
// classes, whole and by rows. Without a device the comparisons skip and the fallback's
// contract is checked instead (the host's families, the same arrays).
#include <gtest/gtest.h>

#include <vector>

#include "breccia/solver/cuda_backend.hpp"
#include "breccia/solver/cuda_families.hpp"
#include "../solver/family_clouds.hpp"

using namespace breccia;
using breccia::testing::Cloud;

namespace {

void expect_device_equals_host(const Cloud& c, int64_t begin, int64_t end) {
  const Families host = build_families(c.x, c.horizon, c.pad, begin, end);
  const Families device = solver::cuda_build_families(c.x, c.horizon, c.pad, begin, end, true);
  EXPECT_EQ(device.offsets, host.offsets) << "rows " << begin << "-" << end;
  EXPECT_EQ(device.neighbors, host.neighbors) << "rows " << begin << "-" << end;
  EXPECT_GT(host.bond_count(), 0u);
}

}  // namespace

TEST(CudaFamilies, EqualTheHostsOnAGradedCloudWholeAndByRows) {
  const Cloud c = breccia::testing::graded(4000);
  const int64_t n = static_cast<int64_t>(c.horizon.size());
  // without a device: the host's families through the fallback (the same call, a note)
  expect_device_equals_host(c, 0, n);
  if (!solver::cuda_device_available()) GTEST_SKIP() << "no CUDA device: the fallback was checked, not the device";
  expect_device_equals_host(c, n / 3, 2 * n / 3);
  expect_device_equals_host(c, n - 1, n);
}

TEST(CudaFamilies, EqualTheHostsOnALattice) {
  if (!solver::cuda_device_available()) GTEST_SKIP() << "no CUDA device";
  const Cloud c = breccia::testing::lattice(30, 1e-3);
  expect_device_equals_host(c, 0, static_cast<int64_t>(c.horizon.size()));
}
