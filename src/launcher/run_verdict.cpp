#include "sensornet/launcher/run_verdict.hpp"

#include <algorithm>

#include "sensornet/launcher/supervisor.hpp"
#include "sensornet/report/run_status.hpp"

namespace sensornet::launcher {
namespace {

using emulator::FaultKind;
using emulator::RunStatus;

bool anyNotSurvived(const std::vector<Fault>& faults) {
  return std::any_of(faults.begin(), faults.end(), [](const Fault& f) { return !f.survived; });
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
  // The launcher's word first (a signal, a fault the run did not survive), then the report's.
  sensornet::report::StatusEvidence seen;
  seen.interrupted = interrupted;
  seen.failed = anyNotSurvived(faults);
  seen.earlier = lookUpWord<RunStatus>(report.status);
  seen.lost = report.lost;
  seen.episodes = report.finished_episodes;
  seen.episodes_complete = report.complete_episodes.value_or(report.finished_episodes);
  if (!seen.interrupted && !seen.failed && !seen.earlier) {
    faults.push_back({FaultKind::ReportInvalid,
                      kFusionCenter,
                      {},
                      {},
                      "the report's status is '" + report.status + "'"});
    seen.failed = true;
  }
  seen.faults = faults.size();
  Verdict verdict;
  verdict.status = sensornet::report::decideRunStatus(seen);
  if (verdict.status == RunStatus::Completed &&
      report.finished_episodes < static_cast<std::uint64_t>(episodes_planned)) {
    faults.push_back({FaultKind::MissingEpisodes,
                      kFusionCenter,
                      {},
                      {},
                      "reports " + std::to_string(report.finished_episodes) + " of " +
                          std::to_string(episodes_planned) + " episodes as finished"});
    seen.failed = true;
    verdict.status = sensornet::report::decideRunStatus(seen);
  }
  verdict.faults = std::move(faults);
  return verdict;
}

}  // namespace sensornet::launcher
