#pragma once
// Where the launcher keeps the files of a run on this host: the "current run" record that lets
// `sensornet replan` and `sensornet status` find the latest launched run without --run-id, the
// default log directory, and the sibling programs it starts.
//
//   ensurePrivateDirectory(userScratchDirectory());           // before using the default folder
//   recordCurrentRun({"run-42", std::nullopt, getpid()});   // at launch
//   std::optional<CurrentRun> run = readCurrentRun();         // in replan/status
//   EmulatorPrograms programs = findEmulatorPrograms();        // coordinator, ...
//
// The scratch folder is /tmp/sensornet-<uid> ($SENSORNET_SCRATCH_DIR overrides it). It is used
// only if it is private, as tmux and ssh-agent check their socket folders: a real directory
// (never a symbolic link) owned by this user that no one else may write to; it is created with
// mode 0700. Otherwise another local user could point it elsewhere before our first run.
// The record lives in $XDG_RUNTIME_DIR/sensornet/current-run, else <scratch>/current-run, in a
// folder checked the same way; logs go to <scratch>/<run id>/ by default.

#include <sys/types.h>

#include <filesystem>
#include <optional>
#include <string>

#include "sensornet/io/output_path.hpp"
#include "sensornet/launcher/launch_plan.hpp"  // EmulatorPrograms

namespace sensornet::launcher {

// The environment variable that moves the scratch folder (tests point it into their own).
inline constexpr const char* kScratchDirVariable = "SENSORNET_SCRATCH_DIR";

struct CurrentRun {
  std::string run_id;
  std::optional<int> domain_id;  // when the run was launched with --domain-id
  pid_t launcher_pid = 0;
};

// $SENSORNET_SCRATCH_DIR if set, else /tmp/sensornet-<uid>: the launcher's scratch folder.
[[nodiscard]] std::filesystem::path userScratchDirectory();
[[nodiscard]] std::filesystem::path currentRunFile();
// <scratch>/<run id> (not created: see ensurePrivateDirectory).
[[nodiscard]] std::filesystem::path defaultLogDirectory(const std::string& run_id);

// Why `dir` is not a private directory of this user (io/output_path.hpp).
using sensornet::privateDirectoryProblem;
// Creates `dir` with mode 0700 if it does not exist (its parent must), then checks that it is
// private; throws InputError naming the directory and what is wrong otherwise.
void ensurePrivateDirectory(const std::filesystem::path& dir);

// Writes the record atomically (a temporary file renamed over it) in a private folder; throws
// when the folder is not private or the record's path is not a regular file.
void recordCurrentRun(const CurrentRun& run);
// The record, or nullopt when there is none, it cannot be read or its folder is not private.
[[nodiscard]] std::optional<CurrentRun> readCurrentRun();
// Removes the record if it still names `run_id` (a later launch may have replaced it).
void forgetCurrentRun(const std::string& run_id);

// The run id the user gave, else the current run's; throws InputError naming --run-id when
// there is neither. Fills `domain_id` from the record when the user gave none.
[[nodiscard]] std::string chooseRunId(const std::string& given, std::optional<int>& domain_id);

// "run-<pid>-<4 random hex digits>".
[[nodiscard]] std::string generateRunId();

// The programs next to this one: in $SENSORNET_BIN_DIR if set; else in the directory of the
// running executable (installed layout, everything in bin/); else in the build tree
// (<exe dir>/../coordinator/coordinator, ...). Throws std::runtime_error naming the missing
// program and where it was looked for.
[[nodiscard]] EmulatorPrograms findEmulatorPrograms();

}  // namespace sensornet::launcher
