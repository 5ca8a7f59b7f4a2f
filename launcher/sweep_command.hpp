#pragma once
// `sensornet sweep EXPERIMENT.yaml`: every cell of an experiment (experiment_file.hpp) planned
// and measured in process (evaluation/sweep.hpp) or, with emulate:, by whole runs of `sensornet
// launch` (sweep_runs.hpp), --jobs cells at a time, with progress and an
// estimate of the time left on standard error. Each finished cell is one line of
// OUT/results.jsonl at once, so Ctrl-C or a crash loses only the cells under way, and the same
// command again runs only the cells not yet there; OUT/results.csv is the table of them all,
// OUT/results.html their page (report/sweep_page.hpp).
//
// Exit: 0 every cell ok; 1 some cell failed (its row says why), the sweep was stopped (Ctrl-C,
// SIGTERM, SIGHUP) or the results cannot be written; 2 bad input (the experiment file, a flag).

#include "sensornet/io/command_line.hpp"

namespace sensornet::launcher {

Subcommand addSweepCommand(CLI::App& app);

}  // namespace sensornet::launcher
