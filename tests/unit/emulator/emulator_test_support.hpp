#pragma once
// Shared fixtures of the emulator unit tests: a small random scenario (n = 3, M = 4, N = 6
// intervals of 0.5 s: plans and rollouts take milliseconds) and a schedule version made by hand.

#include <cstdint>

#include "sensornet/core/rate_schedule.hpp"
#include "sensornet/core/scenario.hpp"
#include "sensornet/emulator/schedule_book.hpp"

namespace sensornet::emulator::test {

inline Scenario smallScenario() {
  RandomPlantSpec spec;
  spec.state_dim = 3;
  spec.sensor_count = 4;
  spec.seed = 9;
  spec.intervals = 6;
  spec.budget = 8.0;
  return generateRandomScenario(spec);
}

inline ScheduleVersion versionOf(std::uint32_t number, const RateSchedule& schedule,
                                 std::uint32_t episode = 0, double at = 0.0) {
  ScheduleVersion v;
  v.version = number;
  v.effective_episode = episode;
  v.effective_time_s = at;
  v.schedule = schedule;
  v.surrogate = "test";
  return v;
}

}  // namespace sensornet::emulator::test
