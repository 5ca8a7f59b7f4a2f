// Timetable against Poisson arrivals on the paper's instances (issue 14, part 3): for random
// scenarios of generateRandomScenario (Section V-A: n = 5, M = 30, T = 3, N = 30, budget 5)
// and their info and cov plans, the deterministic cost J(P) of the schedule's timetable
// (arrival_timetable.hpp) beside the Monte Carlo mean E[J(P)] under Poisson arrivals of the
// same schedule, with its 95% half-width. A timetable sends within one measurement of the
// expected count of every sensor but without the Poisson clumping and gaps; the question is
// whether that never costs more than the Poisson mean.
//
//   timetable_bench [instances=5] [poisson_runs=4000]
//
// Output: one row per (instance, plan) with the difference timetable - Poisson mean and its
// verdict: "lower" or "HIGHER" when the difference exceeds the half-width, else "within".

#include <cstdio>
#include <cstdlib>
#include <string>

#include "sensornet/core/monte_carlo.hpp"
#include "sensornet/planning/planner.hpp"
#include "sensornet/core/scenario.hpp"

namespace {

using namespace sensornet;

struct Comparison {
  double timetable = 0.0;
  double timetable_spread = 0.0;  // std over episodes: zero up to rounding
  double poisson_mean = 0.0;
  double poisson_ci95 = 0.0;
};

Comparison compare(const Scenario& scenario, const RateSchedule& schedule, int runs) {
  MonteCarloOptions options;
  options.simulate_plant = false;
  options.seed = 20261130;
  options.runs = runs;
  const MonteCarloResult poisson = evaluateSchedule(scenario, schedule, options);
  options.arrivals = ArrivalMode::Timetable;
  options.runs = 4;  // deterministic: a few episodes only show that they agree
  const MonteCarloResult timetable = evaluateSchedule(scenario, schedule, options);
  return {timetable.mean, timetable.std_dev, poisson.mean, poisson.ci95};
}

const char* verdict(const Comparison& c) {
  const double diff = c.timetable - c.poisson_mean;
  if (diff > c.poisson_ci95) return "HIGHER";
  if (diff < -c.poisson_ci95) return "lower";
  return "within";
}

}  // namespace

int main(int argc, char** argv) {
  const int instances = argc > 1 ? std::atoi(argv[1]) : 5;
  const int runs = argc > 2 ? std::atoi(argv[2]) : 4000;
  if (instances < 1 || runs < 2) {
    std::fprintf(stderr, "usage: timetable_bench [instances >= 1] [poisson_runs >= 2]\n");
    return 2;
  }
  std::printf("%4s %5s %12s %10s %12s %10s %12s %8s %7s\n", "seed", "plan", "J_timetable",
              "tt_std", "E[J]_poisson", "ci95", "difference", "diff/J", "verdict");
  int higher = 0;
  int lower = 0;
  int rows = 0;
  for (int seed = 1; seed <= instances; ++seed) {
    RandomPlantSpec spec;
    spec.seed = static_cast<std::uint64_t>(seed);
    const Scenario scenario = generateRandomScenario(spec);
    for (const PlanSurrogate surrogate : {PlanSurrogate::Information, PlanSurrogate::Covariance}) {
      PlanRequest request;
      request.surrogate = surrogate;
      const PlanResult plan = planSchedule(scenario, request);
      const Comparison c = compare(scenario, plan.schedule, runs);
      const double diff = c.timetable - c.poisson_mean;
      const char* v = verdict(c);
      higher += std::string(v) == "HIGHER";
      lower += std::string(v) == "lower";
      ++rows;
      std::printf("%4d %5s %12.6g %10.2g %12.6g %10.3g %12.4g %7.2f%% %7s\n", seed,
                  surrogate == PlanSurrogate::Information ? "info" : "cov", c.timetable,
                  c.timetable_spread, c.poisson_mean, c.poisson_ci95, diff,
                  100.0 * diff / c.poisson_mean, v);
      std::fflush(stdout);
    }
  }
  std::printf("%d rows: timetable lower in %d, within the Poisson 95%% half-width in %d, "
              "higher in %d\n",
              rows, lower, rows - lower - higher, higher);
  return 0;
}
