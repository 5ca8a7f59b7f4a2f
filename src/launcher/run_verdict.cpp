#include "sensornet/launcher/run_verdict.hpp"

#include <algorithm>
#include <optional>

#include "sensornet/launcher/supervisor.hpp"

namespace sensornet::launcher {
namespace {

using emulator::FaultKind;
using emulator::RunStatus;

bool anyNotSurvived(const std::vector<Fault>& faults) {
  return std::any_of(faults.begin(), faults.end(), [](const Fault& f) { return !f.survived; });
}

// The status before the count of finished episodes is checked: the launcher's word first.
RunStatus statusFrom(std::vector<Fault>& faults, bool interrupted, const ReportSeen& report) {
  const std::optional<RunStatus> reported = lookUpWord<RunStatus>(report.status);
  if (interrupted) return RunStatus::Interrupted;
  if (anyNotSurvived(faults)) return RunStatus::Failed;
  if (!faults.empty() && reported == RunStatus::Completed) return RunStatus::Degraded;
  if (!reported) {
    faults.push_back({FaultKind::ReportInvalid,
                      kFusionCenter,
                      {},
                      {},
                      "the report's status is '" + report.status + "'"});
    return RunStatus::Failed;
  }
  return *reported;
}

}  // namespace

int exitCodeOf(RunStatus status) {
  switch (status) {
    case RunStatus::Completed:
      return 0;
    case RunStatus::Degraded:
      return kExitDegraded;
    case RunStatus::Failed:
    case RunStatus::Interrupted:
      return 1;
  }
  return 1;
}

Verdict decideVerdict(std::vector<Fault> faults, bool interrupted, const ReportSeen& report,
                      int episodes_planned) {
  if (!report.readable) {
    // A fault of the fusion center's own (it died) already says why its report is missing.
    const bool named = std::any_of(faults.begin(), faults.end(),
                                   [](const Fault& f) { return f.process == kFusionCenter; });
    if (!named) faults.push_back({FaultKind::ReportMissing, kFusionCenter, {}, {}, report.problem});
  }
  Verdict verdict;
  verdict.status = statusFrom(faults, interrupted, report);
  if (verdict.status == RunStatus::Completed &&
      report.finished_episodes < static_cast<std::uint64_t>(episodes_planned)) {
    faults.push_back({FaultKind::MissingEpisodes,
                      kFusionCenter,
                      {},
                      {},
                      "reports " + std::to_string(report.finished_episodes) + " of " +
                          std::to_string(episodes_planned) + " episodes as finished"});
    verdict.status = RunStatus::Failed;
  }
  verdict.faults = std::move(faults);
  return verdict;
}

}  // namespace sensornet::launcher
