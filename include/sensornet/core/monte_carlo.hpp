#pragma once
// The in-process Monte Carlo evaluator of a fixed rate schedule: many independent episodes of
// the exact CD-KF under Poisson arrivals, reduced to the realized cost E[J(P)] of eq. (6) with
// its confidence interval, which Corollary 1 (eq. 22) places between the surrogate costs
// J(P_info) and J(P_cov). Optionally it also simulates the plant (eq. 1) and the measurements
// (eq. 2), so that filter consistency (NEES) and the actual squared error can be checked.
//
//   MonteCarloOptions options;
//   options.runs = 2000;
//   options.seed = 7;
//   const MonteCarloResult mc = evaluateSchedule(scenario, schedule, options);
//   const CostBracket bracket = computeBracket(scenario, schedule);  // surrogate.hpp
//   // expect bracket.info <= mc.mean (+- mc.ci95) <= bracket.cov
//
// With options.arrivals = ArrivalMode::Timetable every episode uses timetableArrivals(schedule).
//
// Reproducibility: episode e draws its arrivals only from
// Rng::keyed(seed, kMonteCarloArrivalStream, e) and its plant and measurement noise only from
// Rng::keyed(seed, kMonteCarloPlantStream, e), and all reductions run in episode order after the
// parallel part, so a seed gives bit-identical results for any thread count.

#include <cstdint>
#include <functional>
#include <vector>

#include "sensornet/core/arrival_mode.hpp"
#include "sensornet/core/rate_schedule.hpp"
#include "sensornet/core/scenario.hpp"

namespace sensornet {

inline constexpr std::uint64_t kMonteCarloArrivalStream = 0x6d632d6172726976ULL;  // "mc-arriv"
inline constexpr std::uint64_t kMonteCarloPlantStream = 0x6d632d706c616e74ULL;    // "mc-plant"

struct MonteCarloOptions {
  int runs = 1000;
  std::uint64_t seed = 1;
  int threads = 0;               // 0 = std::thread::hardware_concurrency()
  bool simulate_plant = true;    // also simulate the truth and measurements: squared error, NEES
  // Poisson arrivals drawn per episode, or the schedule's timetable (arrival_timetable.hpp), the
  // same in every episode: then J(P) is deterministic (std_dev zero up to rounding) and only
  // the plant and measurement noise vary.
  ArrivalMode arrivals = ArrivalMode::Poisson;
  // Optional; called as episodes complete, always from the thread that called evaluateSchedule,
  // last with (runs, runs). An exception it throws stops the workers and propagates.
  std::function<void(int done, int total)> progress;
};

struct MonteCarloResult {
  int runs = 0;
  // Realized J(P) per episode: mean, sample standard deviation, and the 95% half-width
  // 1.96 std_dev / √runs of the normal approximation (infinite when runs < 2).
  double mean = 0.0;
  double std_dev = 0.0;
  double ci95 = 0.0;
  double nees_mean = 0.0;           // mean of e' P(T)^{-1} e, e = x(T) - m(T) (simulate_plant)
  double squared_error_mean = 0.0;  // mean of e' W_T e at T (simulate_plant)
  double arrivals_mean = 0.0;       // mean number of arrivals per episode
  std::vector<double> episode_costs;           // J(P) of each episode, in episode order
  std::vector<double> episode_nees;            // in episode order; empty without simulate_plant
  std::vector<double> episode_squared_errors;  // in episode order; empty without simulate_plant
};

// Runs options.runs episodes over [0, T] on options.threads threads. Throws InputError when the
// options are out of range (runs < 1, threads < 0), the schedule does not fit the scenario
// (sensor count, horizon) or has a negative or non-finite rate, or P0 or some R_j has no
// Cholesky factor. The scenario is otherwise assumed to have passed validateScenario.
[[nodiscard]] MonteCarloResult evaluateSchedule(const Scenario& scenario,
                                                const RateSchedule& schedule,
                                                const MonteCarloOptions& options);

}  // namespace sensornet
