#pragma once
// The realized cost of an episode computed by hand: the CD-KF over its measurements in
// (time, sensor) order, then propagated to the horizon. The fusion center must equal it bit for
// bit whatever order the measurements arrive in; unit tests feed it the fusion's own input, the
// whole-run test the measurements a seeded run's sensors must have drawn.
//
//   EXPECT_EQ(report_cost, sensornet::testing::inOrderCost(scenario, measurements));

#include <algorithm>
#include <tuple>
#include <vector>

#include "sensornet/core/cdkf.hpp"
#include "sensornet/core/scenario.hpp"
#include "sensornet/emulator/episode_fusion.hpp"

namespace sensornet::testing {

[[nodiscard]] inline double inOrderCost(const Scenario& scenario,
                                        std::vector<emulator::FusedMeasurement> all) {
  std::sort(all.begin(), all.end(), [](const auto& a, const auto& b) {
    return std::tie(a.time_s, a.sensor) < std::tie(b.time_s, b.sensor);
  });
  CdKalmanFilter filter(scenario);
  for (const auto& m : all) {
    filter.propagateTo(m.time_s);
    filter.update(m.sensor, m.z);
  }
  filter.propagateTo(scenario.horizon_s);
  return filter.cost();
}

}  // namespace sensornet::testing
