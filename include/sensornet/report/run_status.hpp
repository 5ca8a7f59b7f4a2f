#pragma once
// The one rule that decides a run's status (docs/ARCHITECTURE.md, "Run outcome"), for every way
// a run ends: our fusion center deciding from what it fused, the launcher settling the run with
// what it saw of the processes, an external fusion center's Reports, a restarted or aborted
// run, an interrupted one. Each decider gathers the evidence it has; the rule is the same:
//
//   | evidence, first that holds                                          | status      |
//   |---------------------------------------------------------------------|-------------|
//   | a signal stopped the run (the launcher's, or the deciding process's)  | interrupted |
//   | it could not finish: a fault it did not survive, the coordinator     | failed      |
//   |   gave up, no believable report, fewer episodes than planned         |             |
//   | an earlier decider (the fusion center's report) said interrupted     | interrupted |
//   |   or failed                                                          | or failed   |
//   | any fault, a measurement lost, an incomplete episode, or an earlier  | degraded    |
//   |   decider said degraded                                              |             |
//   | otherwise                                                            | completed   |
//
//   StatusEvidence seen;
//   seen.faults = faults.size();
//   seen.lost = summary.lost;
//   seen.episodes = summary.episodes;
//   seen.episodes_complete = summary.episodes_complete;
//   decideRunStatus(seen);   // completed only when nothing above holds

#include <cstddef>
#include <cstdint>
#include <optional>

#include "sensornet/emulator/vocabulary.hpp"

namespace sensornet::report {

using emulator::RunStatus;

// What the deciding process knows of how the run went.
struct StatusEvidence {
  bool interrupted = false;  // a signal (or the launcher's death) stopped the run
  bool failed = false;       // the run could not finish (see the table above)
  // The status an earlier decider gave (the launcher reads the fusion center's report); none
  // for the first decider.
  std::optional<RunStatus> earlier;
  std::size_t faults = 0;  // faults recorded, survived ones included
  std::uint64_t lost = 0;  // measurements sent and never received
  std::uint64_t episodes = 0;           // finished, complete or not
  std::uint64_t episodes_complete = 0;  // of those, complete
};

[[nodiscard]] RunStatus decideRunStatus(const StatusEvidence& evidence);

}  // namespace sensornet::report
