#pragma once
// A fault the launcher saw itself (a child that died or hung, a signal, the time limit, a report
// it could not read), and the run's whole fault list: the launcher's own first, then what the
// other processes reported, where every reported entry that followed from the run-ending cause
// the launcher knows (a stop it made, a sensor death under --on-sensor-failure stop, a child
// that failed the run) is marked as that cause's consequence with `caused_by`, not counted as a
// fault of its own (docs/guide/faults.md, "Faults in the report").
//
//   Fault killed{FaultKind::ProcessKilled, "sensor_agent-0-2", {0, 1, 2}, at, "killed by ..."};
//   run.faults = faultList({killed}, run.faults);   // stalls after it: caused_by killed
//   run.causeCount();                               // 1 (report/run_record.hpp)

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "sensornet/report/run_record.hpp"
#include "sensornet/emulator/vocabulary.hpp"

namespace sensornet::launcher {

// Where a run was at some wall time: the episode announced last (nullopt before the first or
// after shutdown) and the emulated time in it (nullopt outside [0, T]: announced but not begun,
// or past its end).
struct RunPosition {
  std::optional<std::uint32_t> episode;
  std::optional<double> emulated_time_s;
};

struct Fault {
  Fault() = default;
  Fault(emulator::FaultKind kind_, std::string process_, std::vector<int> sensors_,
        RunPosition at_, std::string detail_)
      : kind(kind_),
        process(std::move(process_)),
        sensors(std::move(sensors_)),
        at(at_),
        detail(std::move(detail_)) {}

  emulator::FaultKind kind = emulator::FaultKind::ProcessFailed;
  std::string process;       // "fusion_center", "sensor_agent-0-2", "coordinator", "sensornet"
  std::vector<int> sensors;  // the sensors the process hosted (sensor agents)
  RunPosition at;            // where the run was
  std::string detail;        // one line: "killed by signal 9 (Killed)"
  bool survived = false;     // the run went on (restarted, or a sensor lost and the policy
                             // applied): it degrades the run instead of failing it
  std::optional<std::uint32_t> schedule_version;  // the version the failure policy published
  // As the report lists it: `sensor` its one sensor, `sensors` when it hosted any, `survived`
  // always, `schedule_version` when one followed.
  [[nodiscard]] report::FaultRecord toRecord() const;
};

// The cause whose consequences the other processes' entries are: the first fault that did not
// leave the run alive (it failed or stopped the run), or nullptr.
[[nodiscard]] const Fault* runEndingCause(const std::vector<Fault>& launcher_faults);

// The fault kinds a stopped run makes the fusion center record: sensors that fell silent or
// whose counts never came, the open episode cut short, the coordinator's abort, the episodes it
// never ran. Other kinds (rejected samples, foreign writers, restarts) have causes of their own.
[[nodiscard]] bool followsFromStop(emulator::FaultKind kind);

// The launcher's faults, then the reported ones; a reported entry of a kind that follows from a
// stop, of an episode still open when the cause struck (the cause's, or the one before it,
// which may still have been owed counts) or later, or of no episode, gets caused_by {kind,
// process} of the run-ending cause, also one the fusion center marked with a cause that itself
// follows from a stop (its run_aborted: the coordinator's abort came from the launcher's cause).
// The other processes record their entries without wall time, so "after the cause" is judged by
// episode.
[[nodiscard]] std::vector<report::FaultRecord> faultList(
    const std::vector<Fault>& launcher_faults, const std::vector<report::FaultRecord>& reported);

}  // namespace sensornet::launcher
