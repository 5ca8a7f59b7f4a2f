// ClockOffsets against the exchange's closed form: with the process's clock θ ahead of the
// fusion center's and one-way delays d1 (out) and d2 (back), t2 = t1 + d1 + θ, t3 = t2 + h,
// t4 = t3 - θ + d2, so the estimate is θ + (d1 - d2) / 2 and the uncertainty (d1 + d2) / 2:
// the true θ lies within it whatever d1, d2 >= 0 are.
#include "sensornet/emulator/clock_offsets.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <random>

namespace sensornet::emulator {
namespace {

constexpr std::int64_t kMs = 1'000'000;

ClockExchange exchange(std::int64_t t1, std::int64_t theta, std::int64_t d1, std::int64_t held,
                       std::int64_t d2) {
  const std::int64_t t2 = t1 + d1 + theta;
  const std::int64_t t3 = t2 + held;
  return {t1, t2, t3, t3 - theta + d2};
}

TEST(ClockOffsets, OneExchangeGivesTheClosedFormAndItsBoundHoldsTheTruth) {
  std::mt19937_64 rng(49);  // fixed: the same 1000 exchanges every run
  std::uniform_int_distribution<std::int64_t> delay(0, 20 * kMs);
  std::uniform_int_distribution<std::int64_t> offset(-3000 * kMs, 3000 * kMs);
  for (int i = 0; i < 1000; ++i) {
    const std::int64_t theta = offset(rng);
    const std::int64_t d1 = delay(rng);
    const std::int64_t d2 = delay(rng);
    const auto o = offsetOf(exchange(1'700'000'000'000'000'000 + i * kMs, theta, d1, 3 * kMs, d2));
    ASSERT_TRUE(o.has_value());
    EXPECT_NEAR(o->offset_s, 1e-9 * static_cast<double>(theta) + 0.5e-9 * static_cast<double>(d1 - d2), 1e-9);
    EXPECT_NEAR(o->uncertainty_s, 0.5e-9 * static_cast<double>(d1 + d2), 1e-9);
    EXPECT_LE(std::abs(o->offset_s - 1e-9 * static_cast<double>(theta)), o->uncertainty_s + 1e-9);
  }
}

TEST(ClockOffsets, TimesThatCannotBeAreRefused) {
  // Answered before it was taken; an answer back before its probe went (a clock stepped between).
  EXPECT_FALSE(offsetOf({0, 10 * kMs, 9 * kMs, 20 * kMs}).has_value());
  EXPECT_FALSE(offsetOf({100 * kMs, 50 * kMs, 60 * kMs, 105 * kMs}).has_value());
  ClockOffsets clocks;
  EXPECT_FALSE(clocks.add("p", {0}, {0, 10 * kMs, 9 * kMs, 20 * kMs}));
  EXPECT_EQ(clocks.refused(), 1u);
  EXPECT_TRUE(clocks.processes().empty());
  EXPECT_FALSE(clocks.measured(0));
}

// The estimate is the exchange of least round trip among the latest kWindow: a slow exchange
// (queued 40 ms one way) does not move it.
TEST(ClockOffsets, TheFastestRecentExchangeIsTheEstimate) {
  ClockOffsets clocks;
  const std::int64_t theta = -2000 * kMs;  // behind by 2 s
  clocks.add("edge", {3, 4}, exchange(0, theta, 40 * kMs, kMs, kMs));
  clocks.add("edge", {3, 4}, exchange(500 * kMs, theta, kMs / 10, kMs, kMs / 5));
  clocks.add("edge", {3, 4}, exchange(1000 * kMs, theta, kMs, kMs, 30 * kMs));
  ASSERT_EQ(clocks.processes().size(), 1u);
  const ClockOffsets::Process& p = clocks.processes()[0];
  EXPECT_EQ(p.exchanges, 3u);
  EXPECT_NEAR(p.best.offset_s, -2.0 - 0.05e-3, 1e-9);
  EXPECT_NEAR(p.best.uncertainty_s, 0.15e-3, 1e-9);
  EXPECT_TRUE(p.best.surelyBeyond(1e-3));
  EXPECT_TRUE(clocks.measured(4));
  EXPECT_FALSE(clocks.measured(5));
}

// A clock stepped mid-run by 1.5 s: within kWindow exchanges the estimate is the new offset,
// and the farthest estimate (what a fault names) is the stepped one.
TEST(ClockOffsets, AClockSteppedMidRunShowsWithinTheWindow) {
  ClockOffsets clocks;
  std::int64_t t1 = 0;
  for (int i = 0; i < 20; ++i, t1 += 500 * kMs) {
    clocks.add("edge", {1}, exchange(t1, 0, kMs / 10, kMs, kMs / 10));  // fast, in step
  }
  EXPECT_FALSE(clocks.processes()[0].best.surelyBeyond(1e-3));
  for (std::size_t i = 0; i < ClockOffsets::kWindow; ++i, t1 += 500 * kMs) {
    clocks.add("edge", {1}, exchange(t1, 1500 * kMs, kMs, kMs, kMs));  // slower, stepped
  }
  const ClockOffsets::Process& p = clocks.processes()[0];
  EXPECT_NEAR(p.best.offset_s, 1.5, 1e-9);
  EXPECT_NEAR(p.farthest.offset_s, 1.5, 1e-9);
  EXPECT_TRUE(p.farthest.surelyBeyond(1e-3));
}

// Within the bound, or not surely beyond it: no fault to name.
TEST(ClockOffsets, OnlyAnOffsetSurelyBeyondTheBoundIsBeyondIt) {
  EXPECT_FALSE((ClockOffset{0.9e-3, 0.0}).surelyBeyond(1e-3));
  EXPECT_FALSE((ClockOffset{-1.5e-3, 0.6e-3}).surelyBeyond(1e-3));
  EXPECT_TRUE((ClockOffset{-1.5e-3, 0.4e-3}).surelyBeyond(1e-3));
  EXPECT_TRUE((ClockOffset{1.5e-3, 0.4e-3}).surelyBeyond(1e-3));
}

}  // namespace
}  // namespace sensornet::emulator
