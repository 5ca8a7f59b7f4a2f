#include "sensornet/report/run_status.hpp"

namespace sensornet::report {

RunStatus decideRunStatus(const StatusEvidence& e) {
  if (e.interrupted) return RunStatus::Interrupted;
  if (e.failed) return RunStatus::Failed;
  if (e.earlier == RunStatus::Interrupted || e.earlier == RunStatus::Failed) return *e.earlier;
  const bool degraded = e.faults > 0 || e.lost > 0 || e.episodes_complete < e.episodes ||
                        e.earlier == RunStatus::Degraded;
  return degraded ? RunStatus::Degraded : RunStatus::Completed;
}

}  // namespace sensornet::report
