#pragma once
// Shared fixtures of the emulator unit tests: a small random scenario (n = 3, M = 4, N = 6
// intervals of 0.5 s: plans and rollouts take milliseconds) and a schedule version made by hand.

#include <cstdint>
#include <utility>
#include <vector>

#include "sensornet/core/rate_schedule.hpp"
#include "sensornet/core/scenario.hpp"
#include "sensornet/emulator/episode_fusion.hpp"
#include "sensornet/emulator/schedule_book.hpp"
#include "support/in_order_cost.hpp"

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
  v.surrogate = SurrogateKind::File;
  return v;
}

// Sensor 0 taken out of service: the other three share the budget.
inline RateSchedule withoutSensorZero(const Scenario& s) {
  Eigen::MatrixXd rates = uniformSchedule(s).rates();
  rates.col(0).setZero();
  rates *= 4.0 / 3.0;
  return RateSchedule(s.horizon_s, rates);
}

// The CD-KF over the measurements in time order, by hand: what the fusion must equal bit for bit.
inline double inOrderCost(const Scenario& scenario, std::vector<FusedMeasurement> all) {
  return sensornet::testing::inOrderCost(scenario, std::move(all));
}

}  // namespace sensornet::emulator::test
