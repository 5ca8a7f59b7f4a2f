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
// A run is a folder <scratch>/<run id>/ (the launcher's default log folder). Its state:
//   live      its launch.lock is held (by a running `sensornet launch`), or no lock file is
//             there and the launcher pid its run.json names is alive;
//   finished  not live, and its report (run.json's "report", else report.json) reads as a run
//             report: its status (completed, degraded, failed, interrupted) is shown;
//   unknown   neither (a launch killed before its report, a folder of something else).
// A folder is removed only while this command holds its launch lock, so a launch of that run id
// cannot start meanwhile, and only a real folder (never a symbolic link) in a private scratch
// folder.
//
// The launcher leaves run.json in the log folder when it starts a run:
//   writeRunRecord(log_dir, {run_id, scenario, episodes, report, pid, started});

#include <sys/types.h>

#include <filesystem>
#include <string>

#include "sensornet/io/command_line.hpp"

namespace sensornet::launcher {

// What the launcher records of a run when it starts it (<log dir>/run.json).
struct RunRecord {
  std::string run_id;
  std::filesystem::path scenario;  // absolute
  int episodes = 0;                // planned
  std::filesystem::path report;    // absolute
  pid_t launcher_pid = 0;
  std::string started_at;  // UTC, "2026-12-01T23:40:02Z"
};

inline constexpr const char* kRunRecordName = "run.json";

// Writes <log_dir>/run.json atomically; a record that cannot be written only costs `sensornet
// runs` the scenario and start time (the caller warns).
void writeRunRecord(const std::filesystem::path& log_dir, const RunRecord& record);

// The current time as RunRecord::started_at spells it.
[[nodiscard]] std::string utcNow();

Subcommand addRunsCommand(CLI::App& app);

}  // namespace sensornet::launcher
