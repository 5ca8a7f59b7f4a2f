#include "sensornet/evaluation/schedule_evaluation.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <fstream>
#include <utility>
#include <vector>

#include "sensornet/core/input_error.hpp"

namespace sensornet::evaluation {
namespace {

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

OpenLoopRun runOpenLoop(const Scenario& scenario, const RateSchedule& schedule,
                        MonteCarloOptions options, ArrivalMode mode) {
  const auto start = std::chrono::steady_clock::now();
  OpenLoopRun run;
  options.arrivals = ArrivalMode::Poisson;
  run.mc = evaluateSchedule(scenario, schedule, options);
  if (mode == ArrivalMode::Timetable) {
    options.arrivals = ArrivalMode::Timetable;
    run.timetable = evaluateSchedule(scenario, schedule, options);
  }
  run.seconds = secondsSince(start);
  return run;
}

ClosedLoopRun runClosedLoop(const Scenario& scenario, const RateSchedule& schedule,
                            const ClosedLoopOptions& loop) {
  const auto start = std::chrono::steady_clock::now();
  ClosedLoopRun run;
  run.closed = simulateClosedLoop(scenario, schedule, loop);
  const std::vector<double> open =
      openLoopCosts(scenario, schedule, loop.runs, loop.seed, loop.threads);
  for (const double c : open) run.open_mean += c / static_cast<double>(open.size());
  run.gain = pairedDifference(run.closed.episode_costs, open);
  run.seconds = secondsSince(start);
  return run;
}

void writeEpisodeCosts(const std::string& path, const std::vector<double>& costs) {
  std::ofstream out(path);
  out.precision(17);
  for (const double c : costs) out << c << "\n";
  out.close();
  if (!out) throw InputError(path, "", "a writable file for --costs");
}

std::function<void(int, int)> decileProgress(std::string what) {
  return [what = std::move(what), last_decile = 0](int done, int total) mutable {
    const int decile = 10 * done / total;
    if (decile > last_decile) {
      last_decile = decile;
      spdlog::info("{}: {}/{} episodes", what, done, total);
    }
  };
}

}  // namespace sensornet::evaluation
