// The one status rule (run_status.hpp) against the run-outcome table of docs/ARCHITECTURE.md:
// each row by a run that ends that way, and two properties over every combination of evidence:
// a run is completed only when no evidence speaks against it, and more evidence never makes a
// status better.
#include "sensornet/report/run_status.hpp"

#include <gtest/gtest.h>

#include <array>
#include <optional>

namespace sensornet::report {
namespace {

// completed < degraded < failed / interrupted: how bad a status is, from the table's exit codes
// (0, 3, 1) read as severity.
int severity(RunStatus s) {
  switch (s) {
    case RunStatus::Completed:
      return 0;
    case RunStatus::Degraded:
      return 1;
    case RunStatus::Failed:
    case RunStatus::Interrupted:
      return 2;
  }
  return 3;
}

StatusEvidence clean(std::uint64_t episodes = 20) {
  StatusEvidence e;
  e.episodes = episodes;
  e.episodes_complete = episodes;
  return e;
}

TEST(RunStatusRule, ACleanRunIsCompleted) { EXPECT_EQ(decideRunStatus(clean()), RunStatus::Completed); }

TEST(RunStatusRule, ALostMeasurementAFaultOrAnIncompleteEpisodeDegradesIt) {
  StatusEvidence lost = clean();
  lost.lost = 1;
  EXPECT_EQ(decideRunStatus(lost), RunStatus::Degraded);
  StatusEvidence fault = clean();
  fault.faults = 1;
  EXPECT_EQ(decideRunStatus(fault), RunStatus::Degraded);
  StatusEvidence incomplete = clean();
  incomplete.episodes_complete = 19;
  EXPECT_EQ(decideRunStatus(incomplete), RunStatus::Degraded);
}

TEST(RunStatusRule, ASignalBeatsEverythingElse) {
  StatusEvidence e = clean();
  e.interrupted = true;
  e.failed = true;
  e.faults = 3;
  e.earlier = RunStatus::Failed;
  EXPECT_EQ(decideRunStatus(e), RunStatus::Interrupted);
}

TEST(RunStatusRule, AFaultNotSurvivedFailsTheRunWhateverTheReportSaid) {
  StatusEvidence e = clean();
  e.failed = true;
  for (const RunStatus earlier : {RunStatus::Completed, RunStatus::Degraded,
                                  RunStatus::Interrupted}) {
    e.earlier = earlier;
    EXPECT_EQ(decideRunStatus(e), RunStatus::Failed) << wordOf(earlier);
  }
}

TEST(RunStatusRule, TheLauncherKeepsAReportThatSaysInterruptedFailedOrDegraded) {
  for (const RunStatus earlier : {RunStatus::Interrupted, RunStatus::Failed, RunStatus::Degraded}) {
    StatusEvidence e = clean();
    e.earlier = earlier;
    EXPECT_EQ(decideRunStatus(e), earlier) << wordOf(earlier);
  }
}

TEST(RunStatusRule, ASurvivedProcessFaultDegradesACompletedReport) {
  StatusEvidence e = clean();
  e.earlier = RunStatus::Completed;
  e.faults = 1;  // a sensor restarted and the run went on
  EXPECT_EQ(decideRunStatus(e), RunStatus::Degraded);
}

TEST(RunStatusRule, AnExternalFusionCentersRunWithNoEpisodeIncompleteAndNoFaultIsCompleted) {
  // An external fusion center's Reports carry no status: the launcher is the first decider.
  StatusEvidence e = clean(4);
  EXPECT_EQ(decideRunStatus(e), RunStatus::Completed);
  e.episodes_complete = 3;
  EXPECT_EQ(decideRunStatus(e), RunStatus::Degraded);
}

// Every combination of the evidence's parts, each present or absent.
TEST(RunStatusRule, CompletedOnlyWithoutAnyEvidenceAndMoreEvidenceNeverHelps) {
  const std::array<std::optional<RunStatus>, 5> earlier{
      std::nullopt, RunStatus::Completed, RunStatus::Degraded, RunStatus::Failed,
      RunStatus::Interrupted};
  for (unsigned bits = 0; bits < 32; ++bits) {
    for (const auto& said : earlier) {
      StatusEvidence e = clean();
      e.interrupted = (bits & 1U) != 0;
      e.failed = (bits & 2U) != 0;
      e.faults = (bits & 4U) != 0 ? 1 : 0;
      e.lost = (bits & 8U) != 0 ? 1 : 0;
      e.episodes_complete = (bits & 16U) != 0 ? e.episodes - 1 : e.episodes;
      e.earlier = said;
      const RunStatus status = decideRunStatus(e);
      const bool nothing_against =
          bits == 0 && (!said || *said == RunStatus::Completed);
      EXPECT_EQ(status == RunStatus::Completed, nothing_against) << "bits " << bits;
      // Adding any one more piece of evidence never lowers the severity.
      for (unsigned more = 1; more < 32; more <<= 1) {
        if ((bits & more) != 0) continue;
        StatusEvidence worse = e;
        if (more == 1) worse.interrupted = true;
        if (more == 2) worse.failed = true;
        if (more == 4) worse.faults = 1;
        if (more == 8) worse.lost = 1;
        if (more == 16) worse.episodes_complete = worse.episodes - 1;
        EXPECT_GE(severity(decideRunStatus(worse)), severity(status))
            << "bits " << bits << " + " << more;
      }
    }
  }
}

}  // namespace
}  // namespace sensornet::report
