#pragma once
// `sensornet runs`: the runs in the scratch folder (/tmp/sensornet-<uid>, or
// $SENSORNET_SCRATCH_DIR), each with its state and what is known of it, and the removal of
// finished ones' folders:
//
//   sensornet runs                      # RUN, STATE, STATUS, STARTED, EPISODES, SCENARIO
//   sensornet runs --json               # {"scratch": DIR, "runs": [{...}, ...]}
//   sensornet runs --remove-finished    # removes the folders of the finished runs
//   sensornet runs rm run-42 run-43     # removes these runs' folders (never a live one)
//
// A run is a folder <scratch>/<run id>/ (the launcher's default log folder); its state (live,
// finished, unknown) is decided by sensornet/launcher/run_folder.hpp.
// A folder is removed only while this command holds its launch lock, so a launch of that run id
// cannot start meanwhile, and only a real folder (never a symbolic link) in a private scratch
// folder.
//
// The launcher leaves run.json in the log folder when it starts a run:
//   writeLaunchRecord(log_dir, {run_id, scenario, episodes, report, pid, started});

#include <sys/types.h>

#include <filesystem>
#include <string>

#include "sensornet/io/command_line.hpp"
#include "sensornet/launcher/run_folder.hpp"  // LaunchRecord

namespace sensornet::launcher {

// Writes <log_dir>/run.json atomically; a record that cannot be written only costs `sensornet
// runs` the scenario and start time (the caller warns).
void writeLaunchRecord(const std::filesystem::path& log_dir, const LaunchRecord& record);

Subcommand addRunsCommand(CLI::App& app);

}  // namespace sensornet::launcher
