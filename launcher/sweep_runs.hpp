#pragma once
// The emulated cells of `sensornet sweep` (an experiment's `emulate:`): each is one whole
// `sensornet launch` of the cell's scenario and schedule, started as a child of this program,
// in OUT/runs/<cell id>/ (scenario.yaml, schedule.json, report.json and its episode log,
// launch.log, logs/). The row gets the run's realized mean and interval over its complete
// episodes, its status and exit code (docs/ARCHITECTURE.md, "Run outcome") and its counts.
//
//   const auto runner = emulatedRunner("sweeps/fig1");
//   json row = evaluation::runSweepCell(cell, threads, stop, runner);
//
// A run that completed or was degraded (exit 0 or 3) is a measurement; one that failed, was
// interrupted or refused its input (exit 1 or 2), or completed no episode, is a failed cell
// whose reason says why. When `stop` is set, the run under way is stopped (SIGTERM: the
// launcher ends it as interrupted and stops its processes) and the cell is not a result.

#include <filesystem>

#include "sensornet/evaluation/sweep.hpp"

namespace sensornet::launcher {

[[nodiscard]] evaluation::EmulatedRunner emulatedRunner(std::filesystem::path out);

}  // namespace sensornet::launcher
