#pragma once
// The weighted trace <W, P(t)> over an episode, as the report's covariance_traces record it for
// the page: of the fusion center's filter over an episode's measurements, and of the two
// surrogates (eq. 11 and eq. 15) of a schedule from P0, on the same grid of times, so that a
// reader sees where the realized covariance ran against the curves that bracket its mean.
//
//   const TraceWeight weight = traceWeight(scenario);               // W, or W_T when W = 0
//   const TraceCurve fused = fusedCovarianceTrace(scenario, fusion.measurements(), weight, 200);
//   const SurrogateTraces curves = surrogateTraces(scenario, version.schedule, weight, 200);
//   json j = traceJson(fused);   // {"times_s": [...], "values": [...]}
//
// The grid is `points` equally spaced times over [0, T], both ends included. The filter's curve is
// right-continuous: at a grid time that is also a measurement time the update is included.
// Between grid points a plot joins the values by straight lines: a downsampled picture, not the
// exact saw-tooth (the realized cost in the report integrates the exact one).

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "sensornet/core/rate_schedule.hpp"
#include "sensornet/core/scenario.hpp"
#include "sensornet/emulator/episode_fusion.hpp"

namespace sensornet::emulator {

// The weight of the plotted trace: the running weight W of eq. (6), or the terminal weight W_T
// when W is zero (the default scenario's cost is terminal only).
struct TraceWeight {
  Eigen::MatrixXd matrix;
  std::string name;  // "W" or "W_T"
};
[[nodiscard]] TraceWeight traceWeight(const Scenario& scenario);

struct TraceCurve {
  std::vector<double> times_s;
  std::vector<double> values;  // <weight, P(t)> at those times
};

// The grid: `points` (>= 2) equally spaced times from 0 to horizon_s.
[[nodiscard]] std::vector<double> traceGrid(double horizon_s, int points);

// <weight, P(t)> of the exact CD-KF over `measurements` (any order; fused in timestamp order,
// covariance only: it does not depend on the measured values).
[[nodiscard]] TraceCurve fusedCovarianceTrace(const Scenario& scenario,
                                              std::vector<FusedMeasurement> measurements,
                                              const TraceWeight& weight, int points);

struct SurrogateTraces {
  TraceCurve info;  // <weight, P_info(t)>, eq. (11)
  TraceCurve cov;   // <weight, Ps(t)>, eq. (15)
};
// The two surrogates of `schedule` from P0, sampled on the grid (rollouts chained from one grid
// time to the next, each to the rollout's own tolerance).
[[nodiscard]] SurrogateTraces surrogateTraces(const Scenario& scenario,
                                              const RateSchedule& schedule,
                                              const TraceWeight& weight, int points);

[[nodiscard]] nlohmann::json traceJson(const TraceCurve& curve);

}  // namespace sensornet::emulator
