#pragma once
// A schedule evaluated offline, as `fusion_center evaluate` prints it (evaluation_summary.hpp):
// the Monte Carlo of the realized cost under Poisson arrivals, with the timetable's beside it
// when the run's arrivals are a timetable; or the closed loop of --replan-every against the
// open-loop plan on the same arrivals (a paired difference). The same seed gives the same
// numbers, whoever calls (the command, a sweep, Python).
//
//   MonteCarloOptions mc;  mc.runs = 2000;  mc.seed = 7;  mc.progress = decileProgress("monte carlo");
//   const OpenLoopRun open = runOpenLoop(scenario, schedule, mc, ArrivalMode::Poisson);
//   const ClosedLoopRun closed = runClosedLoop(scenario, schedule, loop);   // loop.runs, .seed

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "sensornet/core/arrival_mode.hpp"
#include "sensornet/core/monte_carlo.hpp"
#include "sensornet/core/rate_schedule.hpp"
#include "sensornet/core/scenario.hpp"
#include "sensornet/core/student_t.hpp"
#include "sensornet/evaluation/closed_loop.hpp"

namespace sensornet::evaluation {

struct OpenLoopRun {
  MonteCarloResult mc;                         // Poisson arrivals
  std::optional<MonteCarloResult> timetable;  // the same schedule's timetable, when asked for
  double seconds = 0.0;                        // wall time of both
};

// `options.runs` episodes of `schedule` with Poisson arrivals; with `mode` Timetable also the
// timetable's (the same options otherwise).
[[nodiscard]] OpenLoopRun runOpenLoop(const Scenario& scenario, const RateSchedule& schedule,
                                      MonteCarloOptions options, ArrivalMode mode);

struct ClosedLoopRun {
  ClosedLoopResult closed;
  double open_mean = 0.0;  // the open-loop plan on the same arrivals
  SampleMean gain;         // closed minus open, paired episode by episode
  double seconds = 0.0;
};

// The closed loop of `loop` over `loop.runs` episodes of the open-loop plan `schedule`, and that
// plan alone on the same arrivals (openLoopCosts).
[[nodiscard]] ClosedLoopRun runClosedLoop(const Scenario& scenario, const RateSchedule& schedule,
                                          const ClosedLoopOptions& loop);

// Writes `costs` to `path`, one per line with 17 significant digits (a double read back is the
// same number). Throws InputError naming the path (as --costs) when it cannot be written.
void writeEpisodeCosts(const std::string& path, const std::vector<double>& costs);

// A progress callback that logs "<what>: done/total episodes" at each further tenth.
[[nodiscard]] std::function<void(int, int)> decileProgress(std::string what);

}  // namespace sensornet::evaluation
