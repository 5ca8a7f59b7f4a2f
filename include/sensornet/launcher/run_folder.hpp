#pragma once
// What `sensornet runs` says of one run folder (<scratch>/<run id>/, the launcher's default log
// folder), decided from what was found in it: its state, its status and what is known of the
// run. launcher/runs_command.cpp reads the folder (run.json, the launch lock, the report) and
// prints; the decision is here:
//
//   live      its launch.lock is held (by a running `sensornet launch`), or no lock file is
//             there and the launcher pid its run.json names is alive;
//   finished  not live, and its report (run.json's "report", else report.json) reads as a run
//             report with a known status (completed, degraded, failed, interrupted);
//   unknown   neither (a launch killed before its report, a folder of something else).
//
//   RunFolderFacts facts{.folder = dir, .record = runJson};
//   facts.lock = {.exists = true, .held_elsewhere = false, .modified = mtime};
//   facts.report = reportTop;                // read only when not live
//   const RunEntry entry = classifyRun(facts);
//   entry.state;                             // RunState::Finished

#include <sys/types.h>

#include <array>
#include <ctime>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "sensornet/core/words.hpp"

#include "sensornet/report/run_record.hpp"

namespace sensornet::launcher {

enum class RunState { Live, Finished, Unknown };

// The launch record the launcher leaves in the log folder when it starts a run.
inline constexpr const char* kLaunchRecordName = "run.json";

// What the launcher records of a run when it starts it (<log dir>/run.json).
struct LaunchRecord {
  std::string run_id;
  std::filesystem::path scenario;  // absolute
  int episodes = 0;                // planned
  std::filesystem::path report;    // absolute
  pid_t launcher_pid = 0;
  std::string started_at;  // UTC, "2026-12-01T23:40:02Z" (io/utc_time.hpp)
};

[[nodiscard]] nlohmann::json launchRecordJson(const LaunchRecord& record);

// What was found in a run folder.
struct RunFolderFacts {
  std::filesystem::path folder;
  std::optional<nlohmann::json> record;  // run.json, when it is a JSON object
  struct Lock {
    bool exists = false;          // launch.lock is a regular file
    bool held_elsewhere = false;  // a running launch holds it
    std::optional<std::time_t> modified;
  } lock;
  bool launcher_alive = false;  // the process run.json's launcher_pid names is alive
  // Read only when the run is not live (see isLive): the report, without its episodes, when it
  // is one (finishedReportAt), and when live the finished episodes (lines of its episode log).
  std::optional<report::RunRecord> report;
  std::optional<long long> episodes_logged;
};

// One run folder as `sensornet runs` shows it.
struct RunEntry {
  std::string run_id;
  std::filesystem::path folder;
  RunState state = RunState::Unknown;
  std::string status;      // the report's status word (finished runs), "live" or "unknown"
  std::string started_at;  // "" when unknown
  std::string scenario;    // "" when unknown
  std::optional<long long> episodes;
  std::optional<long long> episodes_planned;
  std::filesystem::path report;
  pid_t launcher_pid = 0;
};

// The report a folder's run writes (run.json's "report", else <folder>/report.json) and its
// launcher's pid (0 when run.json names none): what the caller looks at before classifying.
[[nodiscard]] std::filesystem::path reportOf(const RunFolderFacts& facts);
[[nodiscard]] pid_t launcherPidOf(const RunFolderFacts& facts);
// Live: the lock is held elsewhere, or there is no lock and the launcher is alive.
[[nodiscard]] bool isLive(const RunFolderFacts& facts);

[[nodiscard]] RunEntry classifyRun(const RunFolderFacts& facts);
// The report at `path` read without its per_episode entries (a report of millions of episodes
// is never held), or nullopt when there is none or it is not a report this version reads.
[[nodiscard]] std::optional<report::RunRecord> finishedReportAt(const std::filesystem::path& path);

// Oldest start first, runs of unknown start last, then by run id.
void sortRuns(std::vector<RunEntry>& runs);

// "3/20", "?/20", "-" when nothing is known.
[[nodiscard]] std::string episodesText(const RunEntry& entry);
// {"run_id", "folder", "state", "status", "started_at", "scenario", "episodes",
// "episodes_planned", "report"}, unknowns as null.
[[nodiscard]] nlohmann::json runEntryJson(const RunEntry& entry);
// The table `sensornet runs` prints: RUN, STATUS, STARTED, EPISODES, SCENARIO, in columns.
[[nodiscard]] std::string runsTable(const std::vector<RunEntry>& runs);

}  // namespace sensornet::launcher

namespace sensornet {
template <>
struct Words<launcher::RunState> {
  using S = launcher::RunState;
  static constexpr std::array<WordOf<S>, 3> kTable{
      {{S::Live, "live"}, {S::Finished, "finished"}, {S::Unknown, "unknown"}}};
};
}  // namespace sensornet
