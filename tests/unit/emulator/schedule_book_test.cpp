// The schedule book (sensornet/emulator/schedule_book.hpp): versions kept in order, stale ones
// refused, and the episode of a switch split at its effective time.

#include "sensornet/emulator/schedule_book.hpp"

#include <gtest/gtest.h>

#include "emulator_test_support.hpp"

namespace sensornet::emulator {
namespace {

using test::smallScenario;
using test::versionOf;
using test::withoutSensorZero;

TEST(ScheduleBook, KeepsVersionsInOrderAndSplitsTheEpisodeOfASwitch) {
  const Scenario s = smallScenario();
  ScheduleBook book;
  EXPECT_EQ(book.add(versionOf(1, uniformSchedule(s))), ScheduleBook::Outcome::Accepted);
  EXPECT_EQ(book.add(versionOf(3, withoutSensorZero(s), 2, 1.25)), ScheduleBook::Outcome::Accepted);
  EXPECT_EQ(book.add(versionOf(2, uniformSchedule(s), 5, 0.0)), ScheduleBook::Outcome::Stale);
  EXPECT_EQ(book.add(versionOf(3, uniformSchedule(s), 5, 0.0)), ScheduleBook::Outcome::Stale);
  EXPECT_EQ(book.inForce(2, 1.0)->version, 1u);
  EXPECT_EQ(book.inForce(2, 1.25)->version, 3u);
  EXPECT_EQ(book.inForce(3, 0.0)->version, 3u);

  const auto before = book.segments(1, s.horizon_s);
  ASSERT_EQ(before.size(), 1u);
  EXPECT_EQ(before[0].version->version, 1u);
  const auto during = book.segments(2, s.horizon_s);
  ASSERT_EQ(during.size(), 2u);
  EXPECT_EQ(during[0].to_s, 1.25);
  EXPECT_EQ(during[1].from_s, 1.25);
  EXPECT_EQ(during[1].to_s, s.horizon_s);
  EXPECT_EQ(during[1].version->version, 3u);
  EXPECT_TRUE(ScheduleBook().segments(0, 3.0).empty());
}

}  // namespace
}  // namespace sensornet::emulator
