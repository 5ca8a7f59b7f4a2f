#pragma once
// How a launched run ended, decided in one place (DESIGN.md, "Run outcome"): the report's
// status and the launcher's exit code, and the report that says so.
//
// The fusion center decides `completed` or `degraded` from what it saw; the launcher has the
// final word on process faults: a child that died or failed on its own, an interrupt or the time
// limit make the run `failed` (or `interrupted`), and the launcher amends the report: the status,
// and a fault per cause (the process, the sensors it hosted, the episode and emulated time when
// known, a one-line detail). When the fusion center wrote no report (it died), the launcher
// rebuilds one from the episode log beside it (report.jsonl), so every finished episode stays.
// The report is rewritten only atomically and only over a regular file.
//
//   RunEnd end{run_id, report_path, sensor_count, episodes_planned, faults, interrupted};
//   const RunOutcome outcome = settleRun(end);
//   printOutcome(outcome, report_path);   // "run X: failed (1 fault)", ..., "exit code 1"
//   return outcome.exit_code;

#include <filesystem>
#include <nlohmann/json.hpp>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "progress_watcher.hpp"
#include "sensornet/emulator/run_requirements.hpp"

namespace sensornet::launcher {

// Exit codes of `sensornet launch` beyond command_line.hpp's 0, 1 and 2.
inline constexpr int kExitDegraded = 3;  // every episode ran, but a fault cost something

// The exit code of a report status: completed 0, degraded 3, anything else (failed,
// interrupted) 1.
[[nodiscard]] int exitCodeOf(const std::string& status);

// A fault the launcher saw itself.
struct Fault {
  Fault() = default;
  Fault(std::string kind_, std::string process_, std::vector<int> sensors_, RunPosition at_,
        std::string detail_)
      : kind(std::move(kind_)),
        process(std::move(process_)),
        sensors(std::move(sensors_)),
        at(at_),
        detail(std::move(detail_)) {}

  std::string kind;          // process_killed, process_failed, process_hung, interrupted,
                             // timeout, report_missing, episodes_missing
  std::string process;       // "fusion_center", "sensor_agent-0-2", "coordinator", "sensornet"
  std::vector<int> sensors;  // the sensors the process hosted (sensor agents)
  RunPosition at;            // where the run was
  std::string detail;        // one line: "killed by signal 9 (Killed)"
  bool survived = false;     // the run went on (restarted, or a sensor lost and the policy
                             // applied): it degrades the run instead of failing it
  std::optional<std::uint32_t> schedule_version;  // the version the failure policy published
  // {"kind", "process", "sensor" (its one sensor, else null), "sensors" (when it hosted any),
  //  "episode", "emulated_time_s", "detail", "survived", "schedule_version" when one followed}
  [[nodiscard]] nlohmann::json toJson() const;
};

// What the launcher knows when the run is over and every process it started has ended.
struct RunEnd {
  std::string run_id;
  std::filesystem::path report_path;
  int sensor_count = 0;
  int episodes_planned = 0;
  std::vector<Fault> faults;  // the launcher's own
  bool interrupted = false;   // a signal stopped the run
  std::vector<emulator::Requirement> requirements;  // --require: checked against the report
};

struct RunOutcome {
  nlohmann::json report;  // as written (or should have been, see write_problem); without
                          // per_episode when the episode log beside it holds the entries
  std::string status;     // completed, degraded, failed, interrupted
  int exit_code = 1;
  bool amended = false;  // the launcher rewrote the report
  bool rebuilt = false;  // ... from the episode log, the fusion center's being missing
  std::optional<std::string> write_problem;  // the amended report could not be written
  std::vector<emulator::RequirementCheck> checks;  // of RunEnd::requirements, in order
};

// Reads the fusion center's report (or rebuilds it), decides status and exit code, checks the
// --require criteria against the settled report (recorded in it as `requirements`; a failed one
// makes the exit code 4, the status stays what the run was), and rewrites the report when the
// launcher changed it.
[[nodiscard]] RunOutcome settleRun(const RunEnd& end);

// The closing lines on standard output: status and fault count, each fault, episodes complete
// and incomplete, the realized cost against the bracket with meets_bracket (true, false or
// undetermined), sent/received/lost, each --require check, the report's path and the exit code.
void printOutcome(const RunOutcome& outcome, const std::filesystem::path& report_path);
// The same as one JSON line: the report's summary with run_id, status, faults, episodes,
// report, requirements (when given) and exit_code.
void printOutcomeJson(const RunOutcome& outcome, const std::filesystem::path& report_path);

}  // namespace sensornet::launcher
