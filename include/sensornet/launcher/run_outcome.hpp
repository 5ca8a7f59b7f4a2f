#pragma once
// How a launched run ended, decided in one place (docs/ARCHITECTURE.md, "Run outcome"): the report's
// status and the launcher's exit code, and the report that says so.
//
// The decision itself is the launcher core's (run_verdict.hpp: the status from the launcher's
// faults and the report's; fault.hpp: the fault list, a cause once and its consequences marked);
// here the report is read, amended and written. When the fusion center wrote no report (it died), the launcher
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

#include "sensornet/launcher/fault.hpp"
#include "sensornet/launcher/run_verdict.hpp"
#include "sensornet/report/run_requirements.hpp"
#include "sensornet/report/run_record.hpp"

namespace sensornet::launcher {

// What the launcher knows when the run is over and every process it started has ended.
struct RunEnd {
  std::string run_id;
  std::filesystem::path report_path;
  int sensor_count = 0;
  int episodes_planned = 0;
  std::vector<Fault> faults;  // the launcher's own
  bool interrupted = false;   // a signal stopped the run
  std::vector<sensornet::report::Requirement> requirements;  // --require: checked against the report
  std::vector<int> external_sensors;  // --external-sensors: recorded in the report
  // --external-fusion-center: the report is built from the Reports the launcher recorded in the
  // episode log beside report_path (none written by a process of ours).
  bool external_fusion_center = false;
  // --reference-fusion: the reference fusion center's report, compared episode by episode.
  std::filesystem::path reference_report;
  std::uint64_t reports_refused = 0;  // external Reports that did not fit the scenario
  int state_dim = 0;  // n: the NEES band of a rebuilt report (0: none)
  // Where the report goes when report_path refuses it (a full disk): the log folder; empty, or
  // the report's own folder: the system's temporary folder.
  std::filesystem::path fallback_dir;
};

struct RunOutcome {
  report::RunRecord report;  // as written (or should have been, see write_problem); without
                             // per_episode when the episode log beside it holds the entries
  emulator::RunStatus status = emulator::RunStatus::Failed;
  int exit_code = 1;
  bool amended = false;  // the launcher rewrote the report
  bool rebuilt = false;  // ... from the episode log, the fusion center's being missing
  std::optional<std::string> write_problem;  // the amended report could not be written there
  std::optional<std::filesystem::path> written_to;  // ... and was written here instead
  std::vector<sensornet::report::RequirementCheck> checks;  // of RunEnd::requirements, in order
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
