// Throughput of the in-process Monte Carlo evaluator on the first paper's instance (Section V-A:
// n = 5, M = 30, T = 3, N = 30, budget 1'λ <= 5, so about 15 arrivals per episode) under the
// uniform schedule: episodes per second with 1 and 2 threads, with and without simulating the
// plant, the median of several repeats.
//
//   monte_carlo_bench [runs per repeat = 20000] [repeats = 5]

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "sensornet/core/monte_carlo.hpp"
#include "sensornet/core/rate_schedule.hpp"
#include "sensornet/core/scenario.hpp"

namespace {

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const std::size_t mid = values.size() / 2;
  return values.size() % 2 == 1 ? values[mid] : 0.5 * (values[mid - 1] + values[mid]);
}

int positiveArgument(int argc, char** argv, int index, int fallback) {
  if (argc <= index) return fallback;
  const int value = std::atoi(argv[index]);
  return value > 0 ? value : fallback;
}

}  // namespace

int main(int argc, char** argv) {
  using sensornet::MonteCarloOptions;
  const int runs = positiveArgument(argc, argv, 1, 20000);
  const int repeats = positiveArgument(argc, argv, 2, 5);

  const sensornet::Scenario scenario = sensornet::generateRandomScenario({});
  const sensornet::RateSchedule schedule = sensornet::uniformSchedule(scenario);

  std::printf("monte_carlo_bench: n = %d, M = %d, T = %.1f, uniform rate %.4f Hz per sensor, "
              "%d runs x %d repeats\n",
              scenario.stateDim(), scenario.sensorCount(), scenario.horizon_s,
              schedule.rate(0, 0), runs, repeats);
  std::printf("%-8s %-14s %16s %14s %12s\n", "threads", "simulate_plant", "episodes/s (med)",
              "us/episode", "mean J");
  for (const bool plant : {false, true}) {
    for (const int threads : {1, 2}) {
      MonteCarloOptions options;
      options.runs = runs;
      options.threads = threads;
      options.simulate_plant = plant;
      std::vector<double> rates;
      double mean_cost = 0.0;
      for (int r = 0; r < repeats; ++r) {
        options.seed = static_cast<std::uint64_t>(r + 1);
        const auto start = std::chrono::steady_clock::now();
        const sensornet::MonteCarloResult result =
            sensornet::evaluateSchedule(scenario, schedule, options);
        const std::chrono::duration<double> elapsed = std::chrono::steady_clock::now() - start;
        rates.push_back(runs / elapsed.count());
        mean_cost = result.mean;
      }
      const double rate = median(rates);
      std::printf("%-8d %-14s %16.0f %14.2f %12.5f\n", threads, plant ? "yes" : "no", rate,
                  1e6 / rate * threads, mean_cost);
    }
  }
  return 0;
}
