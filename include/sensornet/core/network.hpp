#pragma once
// The emulated network of a scenario (its optional `network:` section) and the faults it
// injects (its `faults:` list): what happens to a measurement between a sensor and the fusion
// center, in emulated seconds. Applied by the sensor agent at the application level, with every
// random choice keyed by (run seed, sensor, episode, seq), so two runs with the same seed drop,
// delay and duplicate the same measurements.
//
//   network:
//     default: {loss: 0.1, delay: {fixed: 0.005, jitter: exponential, mean: 0.010}, duplicate: 0}
//     sensors: {2: {loss: 0.5}}          # per-sensor overrides of single fields, by index
//     outages:                           # the sensor's link is down on [from, to)
//       - {sensor: 1, episodes: all, from: 0.5, to: 1.2}
//   faults:
//     - {kind: crash, sensor: 3, episode: 2, at: 1.0}   # its process exits there
//
// Delivered rates: independent loss p thins a Poisson process of rate λ to one of rate
// λ (1 - p); an outage sets the delivered rate to zero on its window. deliveredSchedule() is
// that thinned schedule, on a grid fine enough to hold every outage edge.

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <vector>

#include "sensornet/core/network_spec.hpp"
#include "sensornet/core/rate_schedule.hpp"

namespace sensornet {

// The rates the fusion center can receive in `episode` under `schedule`: λ_j (1 - loss_j), and
// zero on each outage window of that episode. The grid is the schedule's, refined by the
// smallest integer factor that puts every outage edge on it (validation guarantees one exists,
// see kMaxOutageRefinement).
[[nodiscard]] RateSchedule deliveredSchedule(const RateSchedule& schedule,
                                             const NetworkSpec& network, std::uint32_t episode);

// What `schedule` delivers when sensor j falls silent at emulated time silent_from_s[j] (a dead
// sensor sends nothing; nullopt: it does not, <= 0: the whole episode): its rate is zero from
// there on. The interval holding the instant keeps the fraction of its length before it (its
// rate averaged over the interval, as deliveryFactors() treats an outage off the grid); on a
// grid point, or dead before the episode, the schedule is exact. Sensors beyond the list are
// untouched.
[[nodiscard]] RateSchedule silencedSchedule(const RateSchedule& schedule,
                                            const std::vector<std::optional<double>>& silent_from_s);

// What a network-aware plan (PlanRequest::delivery) assumes the network delivers of each planned
// rate, N x M: (1 - loss_j) times the fraction of interval k outside the outages of sensor j
// that apply to every episode (outages of listed episodes only are left out of planning).
[[nodiscard]] Eigen::MatrixXd deliveryFactors(const Scenario& scenario);

// Outage edges must fall on the schedule's grid refined by at most this factor.
inline constexpr int kMaxOutageRefinement = 1000;

// Largest lognormal jitter sigma (standard deviation of log(delay)) a scenario may ask for.
inline constexpr double kMaxLognormalSigma = 10.0;

// The smallest factor f in [1, kMaxOutageRefinement] that puts both edges of every outage on the
// grid of step T / (N f) (to 1e-6 of a step), or 0 when there is none.
[[nodiscard]] int outageRefinement(double horizon_s, int intervals,
                                   const std::vector<Outage>& outages);

}  // namespace sensornet
