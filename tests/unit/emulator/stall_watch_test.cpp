// StallWatch: gaps between ticks longer than the slack are stalls, and the overlap of a span
// with them is what a process leaves out of its own measurements.

#include "sensornet/emulator/stall_watch.hpp"

#include <gtest/gtest.h>

namespace sensornet::emulator {
namespace {

constexpr std::int64_t kMs = 1'000'000;

TEST(StallWatch, AGapLongerThanTheSlackIsAStall) {
  StallWatch watch(std::chrono::milliseconds(500));
  EXPECT_FALSE(watch.tick(1000 * kMs));  // the first tick has nothing before it
  EXPECT_FALSE(watch.tick(1400 * kMs));
  const auto stall = watch.tick(4400 * kMs);
  ASSERT_TRUE(stall);
  EXPECT_EQ(stall->from_ns, 1400 * kMs);
  EXPECT_EQ(stall->to_ns, 4400 * kMs);
  EXPECT_DOUBLE_EQ(stall->seconds(), 3.0);
  EXPECT_FALSE(watch.tick(4500 * kMs));
}

TEST(StallWatch, MeasuresTheOverlapOfASpanWithItsStalls) {
  StallWatch watch(std::chrono::milliseconds(500));
  (void)watch.tick(0 + 1);
  (void)watch.tick(2000 * kMs);          // stall [1 ns, 2 s)
  (void)watch.tick(2100 * kMs);
  (void)watch.tick(3100 * kMs);          // stall [2.1 s, 3.1 s)
  EXPECT_NEAR(watch.stalledBetween(1000 * kMs, 2500 * kMs), 1.0 + 0.4, 1e-9);
  EXPECT_NEAR(watch.stalledBetween(3100 * kMs, 9000 * kMs), 0.0, 1e-12);
  watch.forgetBefore(2050 * kMs);
  EXPECT_EQ(watch.stalls().size(), 1u);
}

TEST(StallWatch, BusyTimeIsNotAStall) {
  StallWatch watch(std::chrono::milliseconds(500));
  (void)watch.tick(1000 * kMs);
  watch.busyUntil(5000 * kMs);  // a long computation
  EXPECT_FALSE(watch.tick(5100 * kMs));
}

}  // namespace
}  // namespace sensornet::emulator
