// Sensor id lists on the command line (sensornet/emulator/sensor_ids.hpp).

#include "sensornet/emulator/sensor_ids.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "sensornet/core/input_error.hpp"

namespace sensornet::emulator {
namespace {

TEST(SensorIds, ParsesSinglesListsAndRangesAndRejectsTheRest) {
  EXPECT_EQ(parseSensorIds("3", "t"), std::vector<int>{3});
  EXPECT_EQ(parseSensorIds("0-2,7,1", "t"), (std::vector<int>{0, 1, 2, 7}));
  for (const char* bad : {"", "a", "-1", "3-1", "1,,2", "2-", "1.5", "99999999"}) {
    EXPECT_THROW((void)parseSensorIds(bad, "t"), InputError) << bad;
  }
}

}  // namespace
}  // namespace sensornet::emulator
