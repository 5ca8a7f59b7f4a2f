// Settling a launched run's outcome from the files its fusion center left (settleRun): the report
// as written, or rebuilt from the episode log when the fusion center wrote none or one of another
// run, or built from an external fusion center's Reports; the status and exit code by the
// outcome table (docs/ARCHITECTURE.md: 0 completed, 1 failed or interrupted, 3 degraded, 4 a
// --require failed), and what the rewritten report says. Each expectation is worked out here from
// the entries the test writes, not read back from the verdict.

#include "sensornet/launcher/run_outcome.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "../../support/scratch_dir.hpp"
#include "sensornet/emulator/run_report.hpp"
#include "sensornet/launcher/supervisor.hpp"
#include "sensornet/report/report_files.hpp"
#include "sensornet/report/run_record.hpp"
#include "sensornet/report/run_requirements.hpp"

namespace sensornet::launcher {
namespace {

using emulator::FaultKind;
using emulator::RunStatus;
using nlohmann::json;
using testing::ScratchDir;

constexpr int kSensors = 2;
constexpr int kPlanned = 3;
const std::string kRun = "run-outcome-test";

// An episode of two sensors that sent 5 measurements each, `lost` of them lost.
json entry(std::uint32_t episode, double cost, std::uint64_t lost = 0) {
  emulator::EpisodeResult result;
  result.episode = episode;
  result.realized_cost = cost;
  result.realtime_cost = cost;
  result.received_realtime_cost = cost;
  result.bracket = {1.0, 4.0};
  result.delivered_bracket = result.bracket;
  result.versions = {1};
  result.nees = 2.0;
  result.sensors.resize(kSensors);
  for (emulator::SensorTally& s : result.sensors) {
    s.sent = 5;
    s.received = 5;
    s.expected = 5.0;
    s.tallied = true;
  }
  result.sensors[0].received -= lost;
  result.sensors[0].lost = lost;
  result.complete = lost == 0;
  if (lost > 0) result.incomplete_reason = "sensor 0 lost measurements";
  result.latencies_s = std::vector<double>(10 - lost, 1e-4);
  return emulator::episodeEntry(result);
}

// The episode log beside `report`, its lines in the order given (an episode may close late).
void writeLog(const std::filesystem::path& report, const std::vector<json>& entries) {
  sensornet::report::EpisodeLog log(sensornet::report::episodeLogPath(report));
  for (const json& e : entries) log.append(e);
}

// A report as our fusion center writes it: `status`, no faults, per_episode from its log.
void writeFusionReport(const std::filesystem::path& path, const std::string& run_id,
                       const std::string& status, const std::vector<json>& entries) {
  writeLog(path, entries);
  emulator::RunReport report(run_id, "digest", kSensors, 2,
                             sensornet::report::episodeLogPath(path));
  for (const json& e : entries) report.add(e);
  report.addLatencies(std::vector<double>(10 * entries.size(), 1e-4));
  const json head = report.toJsonWithoutEpisodes(status, json::array(), json::array(),
                                                 {{"episodes_planned", kPlanned}});
  std::ofstream out(path);
  report.write(out, head, 2);
}

std::string contents(const std::filesystem::path& path) {
  std::ifstream in(path);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

report::RunRecord writtenRecord(const std::filesystem::path& path) {
  return report::decodeRunRecord(json::parse(contents(path)));
}

std::vector<std::uint32_t> episodesOf(const report::RunRecord& run) {
  std::vector<std::uint32_t> order;
  if (run.per_episode) {
    for (const report::EpisodeRecord& e : *run.per_episode) order.push_back(e.episode);
  }
  return order;
}

RunEnd endOf(const std::filesystem::path& report) {
  RunEnd end;
  end.run_id = kRun;
  end.report_path = report;
  end.sensor_count = kSensors;
  end.episodes_planned = kPlanned;
  return end;
}

TEST(SettleRun, CleanReportStandsAsWrittenAndExitsZero) {
  ScratchDir dir;
  const std::filesystem::path path = dir.file("report.json");
  writeFusionReport(path, kRun, "completed", {entry(0, 2.0), entry(1, 3.0), entry(2, 2.5)});
  const std::string before = contents(path);

  const RunOutcome outcome = settleRun(endOf(path));

  EXPECT_EQ(outcome.status, RunStatus::Completed);
  EXPECT_EQ(outcome.exit_code, 0);
  EXPECT_FALSE(outcome.amended);
  EXPECT_FALSE(outcome.rebuilt);
  EXPECT_TRUE(contents(path) == before);  // not rewritten
  EXPECT_TRUE(outcome.report.faults.empty());
}

TEST(SettleRun, MissingReportIsRebuiltFromTheLogInEpisodeOrder) {
  ScratchDir dir;
  const std::filesystem::path path = dir.file("report.json");
  // Episode 1 closed after episode 2; the fusion center died before writing its report.
  writeLog(path, {entry(0, 2.0), entry(2, 2.5), entry(1, 3.0)});
  RunEnd end = endOf(path);
  end.faults.push_back(
      {FaultKind::ProcessFailed, kFusionCenter, {}, {2, 1.0}, "exited with status 1"});

  const RunOutcome outcome = settleRun(end);

  EXPECT_TRUE(outcome.rebuilt);
  EXPECT_EQ(outcome.status, RunStatus::Failed);
  EXPECT_EQ(outcome.exit_code, 1);
  ASSERT_FALSE(outcome.write_problem.has_value()) << *outcome.write_problem;
  const report::RunRecord written = writtenRecord(path);
  EXPECT_EQ(written.status, RunStatus::Failed);
  EXPECT_TRUE(written.rebuilt_from.has_value());
  EXPECT_EQ(episodesOf(written), (std::vector<std::uint32_t>{0, 1, 2}));  // per_episode[k] is k
  ASSERT_TRUE(written.summary.mean.has_value());
  EXPECT_NEAR(*written.summary.mean, (2.0 + 3.0 + 2.5) / 3.0, 1e-12);
  ASSERT_FALSE(written.faults.empty());
  EXPECT_EQ(written.faults.front().kind, FaultKind::ProcessFailed);
  EXPECT_EQ(written.faults.front().process, kFusionCenter);
}

TEST(SettleRun, ReportOfAnotherRunIsNotBelieved) {
  ScratchDir dir;
  const std::filesystem::path path = dir.file("report.json");
  writeFusionReport(path, "some-other-run", "completed", {entry(0, 2.0)});

  const RunOutcome outcome = settleRun(endOf(path));

  EXPECT_TRUE(outcome.rebuilt);
  EXPECT_EQ(outcome.exit_code, 1);  // the run's own report is missing: not a success
  EXPECT_EQ(writtenRecord(path).run_id, kRun);
}

TEST(SettleRun, SurvivedDeathMakesACleanReportDegraded) {
  ScratchDir dir;
  const std::filesystem::path path = dir.file("report.json");
  writeFusionReport(path, kRun, "completed", {entry(0, 2.0), entry(1, 3.0), entry(2, 2.5)});
  RunEnd end = endOf(path);
  Fault killed{FaultKind::ProcessKilled, "sensor_agent-1", {1}, {1, 0.5}, "killed by signal 9"};
  killed.survived = true;
  end.faults.push_back(killed);

  const RunOutcome outcome = settleRun(end);

  EXPECT_EQ(outcome.status, RunStatus::Degraded);
  EXPECT_EQ(outcome.exit_code, 3);
  EXPECT_TRUE(outcome.amended);
  const report::RunRecord written = writtenRecord(path);
  EXPECT_EQ(written.status, RunStatus::Degraded);
  ASSERT_EQ(written.faults.size(), 1U);
  EXPECT_EQ(written.faults[0].kind, FaultKind::ProcessKilled);
  EXPECT_EQ(written.faults[0].process, "sensor_agent-1");
  EXPECT_EQ(episodesOf(written), (std::vector<std::uint32_t>{0, 1, 2}));  // entries kept
}

TEST(SettleRun, InterruptedRunExitsOne) {
  ScratchDir dir;
  const std::filesystem::path path = dir.file("report.json");
  writeFusionReport(path, kRun, "completed", {entry(0, 2.0)});
  RunEnd end = endOf(path);
  end.interrupted = true;

  const RunOutcome outcome = settleRun(end);

  EXPECT_EQ(outcome.status, RunStatus::Interrupted);
  EXPECT_EQ(outcome.exit_code, 1);
  EXPECT_EQ(writtenRecord(path).status, RunStatus::Interrupted);
}

TEST(SettleRun, FailedRequirementExitsFourAndKeepsTheStatus) {
  ScratchDir dir;
  const std::filesystem::path path = dir.file("report.json");
  writeFusionReport(path, kRun, "completed", {entry(0, 2.0), entry(1, 3.0), entry(2, 2.5)});
  RunEnd end = endOf(path);
  // Every latency is 0.1 ms: p99 <= 1 ms holds, <= 10 us does not.
  end.requirements = sensornet::report::parseRequirements("latency-p99<=1ms,latency-p99<=10us");

  const RunOutcome outcome = settleRun(end);

  EXPECT_EQ(outcome.status, RunStatus::Completed);
  EXPECT_EQ(outcome.exit_code, 4);
  ASSERT_EQ(outcome.checks.size(), 2U);
  EXPECT_TRUE(outcome.checks[0].pass);
  EXPECT_FALSE(outcome.checks[1].pass);
  const json written = json::parse(contents(path));
  ASSERT_TRUE(written.contains("requirements"));
  EXPECT_EQ(written.at("status"), "completed");
}

TEST(SettleRun, ExternalFusionCenterWithLossesIsDegradedByTheOneRule) {
  ScratchDir dir;
  const std::filesystem::path path = dir.file("report.json");
  writeLog(path, {entry(0, 2.0), entry(1, 3.0, 2), entry(2, 2.5)});
  RunEnd end = endOf(path);
  end.external_fusion_center = true;

  const RunOutcome outcome = settleRun(end);

  EXPECT_EQ(outcome.status, RunStatus::Degraded);
  EXPECT_EQ(outcome.exit_code, 3);
  const report::RunRecord written = writtenRecord(path);
  EXPECT_TRUE(written.built_from.has_value());
  ASSERT_TRUE(written.external.has_value());
  EXPECT_TRUE(written.external->fusion_center);
  EXPECT_EQ(written.summary.lost, 2U);
  ASSERT_EQ(written.faults.size(), 1U);
  EXPECT_EQ(written.faults[0].kind, FaultKind::Lost);
}

TEST(SettleRun, CleanExternalFusionCenterCompletes) {
  ScratchDir dir;
  const std::filesystem::path path = dir.file("report.json");
  writeLog(path, {entry(0, 2.0), entry(1, 3.0), entry(2, 2.5)});
  RunEnd end = endOf(path);
  end.external_fusion_center = true;

  const RunOutcome outcome = settleRun(end);

  EXPECT_EQ(outcome.status, RunStatus::Completed);
  EXPECT_EQ(outcome.exit_code, 0);
  EXPECT_TRUE(writtenRecord(path).faults.empty());
}

TEST(SettleRun, AReportPathThatIsNoFileIsNotWrittenThroughButBesideTheLogs) {
  ScratchDir dir;
  const std::filesystem::path path = dir.file("report.json");
  std::filesystem::create_directory(path);  // the fusion center could write nothing there
  RunEnd end = endOf(path);
  end.fallback_dir = dir.file("logs");
  std::filesystem::create_directory(end.fallback_dir);
  end.faults.push_back(
      {FaultKind::ProcessFailed, kFusionCenter, {}, {0, 0.0}, "exited with status 1"});

  const RunOutcome outcome = settleRun(end);

  EXPECT_EQ(outcome.exit_code, 1);
  ASSERT_TRUE(outcome.write_problem.has_value());
  EXPECT_NE(outcome.write_problem->find(path.string()), std::string::npos);
  EXPECT_TRUE(std::filesystem::is_directory(path));
  // Nothing is lost: the report is whole beside the logs, and says the same.
  ASSERT_TRUE(outcome.written_to.has_value());
  EXPECT_EQ(*outcome.written_to, end.fallback_dir / (std::string(kRun) + "-report.json"));
  EXPECT_EQ(writtenRecord(*outcome.written_to).status, RunStatus::Failed);
}

// The fusion center died before its report (a full disk), and its path refuses the launcher's
// too: the report rebuilt from the episode log goes beside the logs with every logged episode;
// when the logs share the report's folder, to the system's temporary folder.
TEST(SettleRun, AReportRefusedWhereAskedGoesElsewhereWithEveryLoggedEpisode) {
  ScratchDir dir;
  const std::filesystem::path path = dir.file("report.json");
  writeFusionReport(path, kRun, "completed", {entry(0, 2.0), entry(1, 3.0), entry(2, 2.5)});
  std::filesystem::remove(path);
  std::filesystem::create_directory(path);  // refuses a file; the episode log beside it stays
  RunEnd end = endOf(path);
  end.faults.push_back(
      {FaultKind::ProcessFailed, kFusionCenter, {}, {2, 0.0}, "exited with status 1"});
  for (const bool logs_beside_the_report : {false, true}) {
    end.fallback_dir = logs_beside_the_report ? dir.file("") : dir.file("logs");
    std::filesystem::create_directories(end.fallback_dir);
    const RunOutcome outcome = settleRun(end);
    ASSERT_TRUE(outcome.written_to.has_value()) << outcome.write_problem.value_or("");
    EXPECT_TRUE(outcome.rebuilt);
    const std::filesystem::path folder = logs_beside_the_report
                                             ? std::filesystem::temp_directory_path()
                                             : end.fallback_dir;
    EXPECT_EQ(outcome.written_to->parent_path(), folder);
    EXPECT_EQ(episodesOf(writtenRecord(*outcome.written_to)),
              (std::vector<std::uint32_t>{0, 1, 2}));
    std::filesystem::remove(*outcome.written_to);
  }
}

}  // namespace
}  // namespace sensornet::launcher
