#pragma once
// Where the launcher keeps the files of a run on this host: the "current run" record that lets
// `sensornet replan` and `sensornet status` find the latest launched run without --run-id, the
// default log directory, and the sibling programs it starts.
//
//   recordCurrentRun({"run-42", std::nullopt, getpid()});   // at launch
//   std::optional<CurrentRun> run = readCurrentRun();         // in replan/status
//   EmulatorPrograms programs = findEmulatorPrograms();        // coordinator, ...
//
// The record lives in $XDG_RUNTIME_DIR/sensornet/current-run, else
// /tmp/sensornet-<uid>/current-run; logs in /tmp/sensornet-<uid>/<run id>/ by default.

#include <sys/types.h>

#include <filesystem>
#include <optional>
#include <string>

namespace sensornet::launcher {

struct CurrentRun {
  std::string run_id;
  std::optional<int> domain_id;  // when the run was launched with --domain-id
  pid_t launcher_pid = 0;
};

// /tmp/sensornet-<uid>: the launcher's scratch directory on this host.
[[nodiscard]] std::filesystem::path userScratchDirectory();
[[nodiscard]] std::filesystem::path currentRunFile();
[[nodiscard]] std::filesystem::path defaultLogDirectory(const std::string& run_id);

// Writes the record atomically (a temporary file renamed over it).
void recordCurrentRun(const CurrentRun& run);
// The record, or nullopt when there is none or it cannot be read.
[[nodiscard]] std::optional<CurrentRun> readCurrentRun();
// Removes the record if it still names `run_id` (a later launch may have replaced it).
void forgetCurrentRun(const std::string& run_id);

// The run id the user gave, else the current run's; throws InputError naming --run-id when
// there is neither. Fills `domain_id` from the record when the user gave none.
[[nodiscard]] std::string chooseRunId(const std::string& given, std::optional<int>& domain_id);

// "run-<pid>-<4 random hex digits>".
[[nodiscard]] std::string generateRunId();

struct EmulatorPrograms {
  std::filesystem::path coordinator;
  std::filesystem::path fusion_center;
  std::filesystem::path sensor_agent;
};

// The programs next to this one: in $SENSORNET_BIN_DIR if set; else in the directory of the
// running executable (installed layout, everything in bin/); else in the build tree
// (<exe dir>/../coordinator/coordinator, ...). Throws std::runtime_error naming the missing
// program and where it was looked for.
[[nodiscard]] EmulatorPrograms findEmulatorPrograms();

}  // namespace sensornet::launcher
