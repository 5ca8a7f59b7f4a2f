// The sensors' arrival timelines (sensornet/emulator/sensor_timeline.hpp): a new schedule
// version changes only what comes after its effective time, and the counts match the schedule's
// Poisson expectations.

#include "sensornet/emulator/sensor_timeline.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "emulator_test_support.hpp"
#include "sensornet/emulator/schedule_book.hpp"

namespace sensornet::emulator {
namespace {

using test::smallScenario;
using test::versionOf;
using test::withoutSensorZero;

// Recomputing a timeline after a new version must not change what was drawn before its
// effective time, and after it only the new rates count (sensor 0 is silent).
TEST(SensorTimeline, ANewVersionChangesOnlyWhatComesAfterItsEffectiveTime) {
  const Scenario s = smallScenario();
  const EmulatedPlant plant(s, 4);
  const std::vector<int> sensors = {0, 1, 2, 3};
  const double at = plant.timeOf(plant.tickAt(1.3));
  for (std::uint32_t episode = 0; episode < 50; ++episode) {
    ScheduleBook book;
    (void)book.add(versionOf(1, uniformSchedule(s)));
    const auto before = sensorTimeline(book, plant, 4, episode, sensors, s.horizon_s);
    (void)book.add(versionOf(2, withoutSensorZero(s), episode, at));
    const auto after = sensorTimeline(book, plant, 4, episode, sensors, s.horizon_s);
    std::vector<TimedArrival> head_before, head_after;
    for (const auto& a : before)
      if (a.time_s < at) head_before.push_back(a);
    for (const auto& a : after)
      if (a.time_s < at) head_after.push_back(a);
    ASSERT_EQ(head_before.size(), head_after.size()) << "episode " << episode;
    for (std::size_t i = 0; i < head_before.size(); ++i) {
      EXPECT_EQ(head_before[i].tick, head_after[i].tick);
      EXPECT_EQ(head_before[i].sensor, head_after[i].sensor);
      EXPECT_EQ(head_after[i].version, 1u);
    }
    for (const auto& a : after) {
      if (a.time_s >= at) {
        EXPECT_EQ(a.version, 2u);
        EXPECT_NE(a.sensor, 0);
      }
    }
  }
}

// Counts over many episodes against the schedule: Pearson's chi-square at level 0.001.
TEST(SensorTimeline, CountsPerSensorMatchTheScheduleInChiSquare) {
  const Scenario s = smallScenario();
  const EmulatedPlant plant(s, 4);
  ScheduleBook book;
  Eigen::MatrixXd rates = uniformSchedule(s).rates();
  rates.col(1) *= 0.25;  // unequal rates
  (void)book.add(versionOf(1, RateSchedule(s.horizon_s, rates)));
  const int episodes = 400;
  Eigen::VectorXd counts = Eigen::VectorXd::Zero(4);
  for (std::uint32_t e = 0; e < episodes; ++e) {
    for (const auto& a : sensorTimeline(book, plant, 11, e, {0, 1, 2, 3}, s.horizon_s)) {
      counts(a.sensor) += 1.0;
    }
  }
  const Eigen::VectorXd expected =
      episodes * book.latest().schedule.expectedCounts(0.0, s.horizon_s);
  const double statistic = ((counts - expected).array().square() / expected.array()).sum();
  EXPECT_LT(statistic, 18.47) << counts.transpose() << " vs " << expected.transpose();  // χ²(4)
}

}  // namespace
}  // namespace sensornet::emulator
