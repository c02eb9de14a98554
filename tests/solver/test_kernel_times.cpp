// The host side of --kernel-times (kernel_times.hpp): the per-name sums the CUDA events are
// resolved into, and the table breccia-solve prints. The events themselves need a GPU
// (test_solver_cuda, CudaBackend.KernelTimes*).
#include <gtest/gtest.h>

#include <string>

#include "breccia/solver/kernel_times.hpp"

using namespace breccia::solver;

TEST(KernelTimes, LaunchesAreSummedPerNameAndSortedByTotal) {
  KernelTimeTable table;
  for (int step = 0; step < 4; ++step) {
    table.add("start_of_step_kernel", 1e-5);
    table.add("force_kernel", 2.5e-4);
    table.add(std::string("clear body forces"), 2e-6);  // a name that is not a literal
    table.step_done();
  }
  table.add("measure reduction", 3e-5);  // a history row's measure: once in the four steps
  const KernelTimes t = table.times(7);
  EXPECT_EQ(t.warmup_steps, 7);
  EXPECT_EQ(t.steps_timed, 4);
  ASSERT_EQ(t.kernels.size(), 4u);
  EXPECT_EQ(t.kernels[0].name, "force_kernel");
  EXPECT_EQ(t.kernels[0].launches, 4);
  EXPECT_DOUBLE_EQ(t.kernels[0].seconds, 4 * 2.5e-4);
  EXPECT_EQ(t.kernels[1].name, "start_of_step_kernel");
  EXPECT_EQ(t.kernels[2].name, "measure reduction");
  EXPECT_EQ(t.kernels[2].launches, 1);
  EXPECT_EQ(t.kernels[3].name, "clear body forces");
  EXPECT_DOUBLE_EQ(t.seconds(), 4 * (1e-5 + 2.5e-4 + 2e-6) + 3e-5);
}

TEST(KernelTimes, EqualTotalsAreOrderedByName) {
  KernelTimeTable table;
  table.add("b", 1e-3);
  table.add("a", 1e-3);
  const KernelTimes t = table.times(0);
  ASSERT_EQ(t.kernels.size(), 2u);
  EXPECT_EQ(t.kernels[0].name, "a");
  EXPECT_EQ(t.kernels[1].name, "b");
}

TEST(KernelTimes, TableGivesMicrosecondsPerTimedStepAndShares) {
  KernelTimeTable table;
  for (int step = 0; step < 2; ++step) {
    table.add("force_kernel", 2e-3);   // 2,000 us a step: 80 % of the kernels' time
    table.add("start_of_step_kernel", 5e-4);
    table.step_done();
  }
  const std::string text = kernel_times_table(table.times(100));
  EXPECT_NE(text.find("2 steps timed after 100 warm-up steps"), std::string::npos) << text;
  EXPECT_NE(text.find("2000.00"), std::string::npos) << text;
  EXPECT_NE(text.find("80.0%"), std::string::npos) << text;
  EXPECT_NE(text.find("500.00"), std::string::npos) << text;
  EXPECT_NE(text.find("2500.00"), std::string::npos) << "the total per step: " << text;
}
