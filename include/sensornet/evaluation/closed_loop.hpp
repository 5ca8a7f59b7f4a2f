#pragma once
// Scheduling in closed loop (`--replan-every DT`): a receding horizon over each episode. Every
// episode starts with the run's open-loop plan; at each multiple of DT of emulated time the rest
// of the episode is planned again, with the run's surrogate, from the fused covariance of that
// moment carried to the switch tick one switch margin ahead (Replanner::replanTail: the same
// planner and switch rule as any live change), and from the next episode the open-loop plan is
// in force again.
//
// The coordinator applies the policy live (CoordinatorConfig::replan_every_s); this file holds
// what both it and the offline simulation need, and the offline simulation itself: the same
// Replanner, no DDS and no wall clock, over thousands of episodes.
//
//   ClosedLoopOptions options;
//   options.replan_every_s = 0.5;
//   options.surrogate = PlanSurrogate::Information;
//   const ClosedLoopResult closed = simulateClosedLoop(scenario, open_loop_plan, options);
//   // closed.episode_costs[e] is paired with the open-loop cost of episode e of the same seed
//   // (openLoopCosts): the same unit-rate points (TimeChangedArrivals, poisson_arrivals.hpp).
//
// Offline, planning takes no time: the tail takes effect exactly at the first tick at or after
// t + switch margin (emulated). Live, a plan that outlasts half the margin moves the switch
// later (replanner.hpp) and the fused covariance lags the emulated clock by the fusion center's
// pace; the two agree in distribution (tests/integration/emulation/closed_loop_test.cpp).

#include <cstdint>
#include <functional>
#include <vector>

#include "sensornet/planning/planner.hpp"
#include "sensornet/core/rate_schedule.hpp"
#include "sensornet/core/scenario.hpp"
#include "sensornet/emulator/replanner.hpp"

namespace sensornet::evaluation {

// The instants of an episode at which the tail is re-planned: DT, 2 DT, ... strictly below T
// (none when DT >= T). Throws InputError unless DT is a finite number > 0.
[[nodiscard]] std::vector<double> replanInstants(double every_s, double horizon_s);

struct ClosedLoopOptions {
  double replan_every_s = 1.0;  // DT, emulated seconds
  PlanSurrogate surrogate = PlanSurrogate::Information;
  // The switch margin in wall seconds and the run's time scale: the tail takes effect
  // switch_margin_s * time_scale emulated seconds after its instant, as in the live run.
  emulator::ReplannerOptions replanner;
  int runs = 1000;
  std::uint64_t seed = 1;
  int threads = 0;  // 0: one per core
  // Optional; called as episodes complete, from the calling thread, last with (runs, runs).
  std::function<void(int done, int total)> progress;
};

struct ClosedLoopResult {
  int runs = 0;
  double mean = 0.0;     // of J(P), the realized cost of eq. (6)
  double std_dev = 0.0;  // over episodes
  double ci95 = 0.0;     // t_{0.975, runs-1} std_dev / sqrt(runs)
  std::vector<double> episode_costs;  // in episode order
  double tails_mean = 0.0;            // re-planned tails that took effect, per episode
  long long refused = 0;   // instants whose plan the Replanner refused (no tail published)
  double arrivals_mean = 0.0;
};

// Runs the policy over `runs` episodes of `open_loop` (every episode's plan at its start).
// Episode e's arrivals are TimeChangedArrivals(M, seed, e): deterministic for a seed, for any
// thread count. Throws InputError for options out of range or a schedule that does not fit.
[[nodiscard]] ClosedLoopResult simulateClosedLoop(const Scenario& scenario,
                                                  const RateSchedule& open_loop,
                                                  const ClosedLoopOptions& options);

// J(P) of episodes 0..runs-1 of `seed` under a fixed schedule, on the same unit-rate points as
// simulateClosedLoop: a paired open-loop comparison.
[[nodiscard]] std::vector<double> openLoopCosts(const Scenario& scenario,
                                                const RateSchedule& schedule, int runs,
                                                std::uint64_t seed, int threads);

}  // namespace sensornet::evaluation
