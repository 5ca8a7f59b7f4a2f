// The run's status and exit code against docs/ARCHITECTURE.md's outcome table (0 completed, 1 failed or
// interrupted, 3 degraded, 4 a --require failed), and the fault list that names a cause once:
// what the fusion center recorded because of the run-ending cause is marked as its consequence.

#include "sensornet/launcher/run_verdict.hpp"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "sensornet/report/fault_causes.hpp"
#include "sensornet/emulator/run_report.hpp"
#include "sensornet/report/run_requirements.hpp"
#include "sensornet/launcher/supervisor.hpp"

namespace sensornet::launcher {
namespace {

using emulator::FaultKind;
using emulator::RunStatus;
using nlohmann::json;

constexpr int kPlanned = 20;

ReportSeen reported(const std::string& status, std::uint64_t finished = kPlanned) {
  ReportSeen seen;
  seen.readable = true;
  seen.status = status;
  seen.finished_episodes = finished;
  return seen;
}

// The report the launcher could not believe or find (it was rebuilt), and why.
ReportSeen unreadable(const std::string& problem, const std::string& status,
                      std::uint64_t finished) {
  ReportSeen seen;
  seen.problem = problem;
  seen.status = status;
  seen.finished_episodes = finished;
  return seen;
}

Fault survivedDeath() {
  Fault f{FaultKind::ProcessKilled, "sensor_agent-0-2", {0, 1, 2}, {2, 0.5}, "killed"};
  f.survived = true;
  return f;
}

Fault failedChild() {
  return {FaultKind::ProcessFailed, kCoordinator, {}, {3, 1.0}, "exited with status 1"};
}

TEST(RunVerdict, CleanReportIsCompletedExitZero) {
  const Verdict v = decideVerdict({}, false, reported("completed"), kPlanned);
  EXPECT_EQ(v.status, RunStatus::Completed);
  EXPECT_EQ(exitCodeOf(v.status), 0);
  EXPECT_TRUE(v.faults.empty());
}

TEST(RunVerdict, DegradedReportExitsThree) {
  const Verdict v = decideVerdict({}, false, reported("degraded"), kPlanned);
  EXPECT_EQ(v.status, RunStatus::Degraded);
  EXPECT_EQ(exitCodeOf(v.status), 3);
}

TEST(RunVerdict, SurvivedDeathDegradesACompletedReport) {
  const Verdict v = decideVerdict({survivedDeath()}, false, reported("completed"), kPlanned);
  EXPECT_EQ(v.status, RunStatus::Degraded);
  EXPECT_EQ(exitCodeOf(v.status), 3);
}

TEST(RunVerdict, FaultTheRunDidNotSurviveFailsItExitOne) {
  const Verdict v = decideVerdict({failedChild()}, false, reported("completed"), kPlanned);
  EXPECT_EQ(v.status, RunStatus::Failed);
  EXPECT_EQ(exitCodeOf(v.status), 1);
}

TEST(RunVerdict, SignalMakesTheRunInterruptedExitOne) {
  const Fault signal{FaultKind::Interrupted, kLauncherProcess, {}, {}, "interrupted by SIGINT"};
  const Verdict v = decideVerdict({signal}, true, reported("interrupted", 3), kPlanned);
  EXPECT_EQ(v.status, RunStatus::Interrupted);
  EXPECT_EQ(exitCodeOf(v.status), 1);
  EXPECT_EQ(v.faults.size(), 1u) << "no missing_episodes for a run that was stopped";
}

TEST(RunVerdict, FailedReportStaysFailed) {
  EXPECT_EQ(decideVerdict({}, false, reported("failed"), kPlanned).status, RunStatus::Failed);
}

TEST(RunVerdict, MissingReportFailsTheRunAndSaysSo) {
  const Verdict v =
      decideVerdict({}, false, unreadable("wrote no report at r.json", "failed", 0), kPlanned);
  EXPECT_EQ(v.status, RunStatus::Failed);
  ASSERT_EQ(v.faults.size(), 1u);
  EXPECT_EQ(v.faults[0].kind, FaultKind::ReportMissing);
  EXPECT_EQ(v.faults[0].detail, "wrote no report at r.json");
}

TEST(RunVerdict, MissingReportOfADeadFusionCenterIsNotASecondFault) {
  const Fault died{FaultKind::ProcessKilled, kFusionCenter, {}, {}, "killed"};
  const Verdict v = decideVerdict({died}, false, unreadable("wrote no report", "failed", 0), kPlanned);
  EXPECT_EQ(v.faults.size(), 1u);
}

TEST(RunVerdict, UnknownStatusIsAnInvalidReport) {
  const Verdict v = decideVerdict({}, false, reported("splendid"), kPlanned);
  EXPECT_EQ(v.status, RunStatus::Failed);
  ASSERT_EQ(v.faults.size(), 1u);
  EXPECT_EQ(v.faults[0].kind, FaultKind::ReportInvalid);
}

TEST(RunVerdict, CompletedWithEpisodesMissingFails) {
  const Verdict v = decideVerdict({}, false, reported("completed", 19), kPlanned);
  EXPECT_EQ(v.status, RunStatus::Failed);
  ASSERT_EQ(v.faults.size(), 1u);
  EXPECT_EQ(v.faults[0].kind, FaultKind::MissingEpisodes);
}

// Exit 4: a --require criterion failed on a run that completed or was degraded; a failed run
// stays 1.
TEST(RunVerdict, FailedRequirementExitsFourUnlessTheRunFailed) {
  const auto checks =
      sensornet::report::checkRequirements(
          sensornet::report::parseRequirements("no-faults"),
          json{{"run_id", "r"}, {"status", "degraded"}, {"summary", json::object()},
               {"faults", json::array({{{"kind", "lost"}}})}});
  ASSERT_EQ(checks.size(), 1u);
  EXPECT_FALSE(checks[0].pass);
  EXPECT_EQ(sensornet::report::gatedExitCode(exitCodeOf(RunStatus::Completed), checks), 4);
  EXPECT_EQ(sensornet::report::gatedExitCode(exitCodeOf(RunStatus::Degraded), checks), 4);
  EXPECT_EQ(sensornet::report::gatedExitCode(exitCodeOf(RunStatus::Failed), checks), 1);
  EXPECT_EQ(sensornet::report::gatedExitCode(exitCodeOf(RunStatus::Interrupted), checks), 1);
}

// faultList over the report's entries as JSON, as they are written and read: through the one
// codec both ways.
json faultList(const std::vector<Fault>& launcher_faults, const json& reported) {
  std::vector<sensornet::report::FaultRecord> records;
  for (const json& entry : reported) records.push_back(sensornet::report::decodeFault(entry));
  return sensornet::report::encode(launcher::faultList(launcher_faults, records));
}

json entry(const std::string& kind, json episode, json sensor = nullptr) {
  return {{"kind", kind},       {"process", "fusion_center"}, {"sensor", sensor},
          {"episode", episode}, {"emulated_time_s", nullptr}, {"detail", "..."}};
}

// Under --on-sensor-failure stop the fusion center records a stall for every healthy sensor of
// the open episode and the coordinator's abort: consequences of the one death.
TEST(FaultList, EntriesAfterTheRunEndingCauseAreItsConsequences) {
  Fault death{FaultKind::ProcessKilled, "sensor_agent-0-2", {0, 1, 2}, {2, 0.3}, "killed"};
  // Episode 0 was closed before the death in episode 2: its stall is a cause of its own; episode
  // 1 may still have been owed counts (two episodes outstanding at most).
  const json seen = json::array({entry("stall", 0, 4), entry("stall", 1, 3), entry("stall", 2, 4),
                                 entry("stall", 3, 5), entry("run_aborted", nullptr),
                                 entry("rejected", nullptr)});
  const json faults = faultList({death}, seen);
  ASSERT_EQ(faults.size(), 7u);
  EXPECT_EQ(faults[0]["process"], "sensor_agent-0-2") << "the launcher's cause comes first";
  EXPECT_FALSE(faults[1].contains("caused_by"));
  for (const std::size_t i : {2u, 3u, 4u, 5u}) {
    ASSERT_TRUE(faults[i].contains("caused_by")) << faults[i].dump();
    EXPECT_EQ(faults[i]["caused_by"],
              (json{{"kind", "process_killed"}, {"process", "sensor_agent-0-2"}}));
  }
  EXPECT_FALSE(faults[6].contains("caused_by")) << "rejected samples have causes of their own";
  EXPECT_EQ(sensornet::report::causeCount(faults), 3u);
}

// The fusion center records sensor_died from the coordinator's notice (what a run without a
// launcher has); where the launcher saw the process end, its own entry stands for those sensors.
TEST(FaultList, TheLaunchersDeathReplacesTheFusionCentersAccountOfIt) {
  Fault death{FaultKind::ProcessKilled, "sensor_agent-3-5", {3, 4, 5}, {2, 0.3}, "killed"};
  death.survived = true;
  const json seen = json::array({entry("sensor_died", 2, 3), entry("sensor_died", 2, 4),
                                 entry("sensor_died", 2, 1), entry("stall", 2, 5)});
  const json faults = faultList({death}, seen);
  ASSERT_EQ(faults.size(), 3u) << faults.dump();
  EXPECT_EQ(faults[0]["process"], "sensor_agent-3-5");
  EXPECT_EQ(faults[1]["kind"], "sensor_died") << "sensor 1 was no process of the launcher's";
  EXPECT_EQ(faults[1]["sensor"], 1);
  EXPECT_EQ(faults[2]["kind"], "stall") << "other kinds of the same sensors stay";
}

TEST(FaultList, InterruptBeforeTheFirstEpisodeOwnsEveryStopEntry) {
  const Fault signal{FaultKind::Interrupted, kLauncherProcess, {}, {}, "interrupted by SIGINT"};
  const json faults = faultList({signal}, json::array({entry("cut_short", 0, 1)}));
  EXPECT_EQ(faults[1]["caused_by"]["kind"], "interrupted");
  EXPECT_EQ(sensornet::report::causeCount(faults), 1u);
}

// The fusion center marks its cut as caused by the coordinator's abort; the abort came from the
// launcher's cause (a Ctrl-C), which both are then counted with. A mark the fusion center made
// for a cause of its own kind (a death it recorded) is left as it is.
TEST(FaultList, TheLauncherNamesTheRootOfACauseTheFusionCenterMarked) {
  const Fault signal{FaultKind::Interrupted, kLauncherProcess, {}, {2, 0.5}, "interrupted by SIGINT"};
  json cut = entry("cut_short", 2);
  cut["caused_by"] = {{"kind", "run_aborted"}, {"process", "coordinator"}};
  json lost = entry("lost", 3, 1);  // of a kind that follows from a stop, marked otherwise
  lost["caused_by"] = {{"kind", "process_killed"}, {"process", "sensor_agent-1"}};
  const json faults = faultList({signal}, json::array({entry("run_aborted", nullptr), cut, lost}));
  ASSERT_EQ(faults.size(), 4u);
  const json root = {{"kind", "interrupted"}, {"process", "sensornet"}};
  EXPECT_EQ(faults[1]["caused_by"], root);
  EXPECT_EQ(faults[2]["caused_by"], root) << "re-pointed to the root cause";
  EXPECT_EQ(faults[3]["caused_by"], lost["caused_by"]);
}

TEST(FaultList, SurvivedFaultsLeaveTheOthersCausesOfTheirOwn) {
  const json faults = faultList({survivedDeath()}, json::array({entry("lost", 3, 4)}));
  EXPECT_FALSE(faults[1].contains("caused_by"));
  EXPECT_EQ(sensornet::report::causeCount(faults), 2u);
}

TEST(FaultList, NoFaultsCriterionCountsCauses) {
  const Fault signal{FaultKind::Interrupted, kLauncherProcess, {}, {}, "interrupted by SIGINT"};
  const json report = {{"run_id", "r"},
                       {"status", "failed"},
                       {"summary", json::object()},
                       {"faults", faultList({signal}, json::array({entry("stall", 1, 0)}))}};
  EXPECT_EQ(sensornet::report::causeCount(report["faults"]), 1u);
  const auto checks = sensornet::report::checkRequirements(sensornet::report::parseRequirements("no-faults"), report);
  EXPECT_FALSE(checks.at(0).pass);
}

}  // namespace
}  // namespace sensornet::launcher
