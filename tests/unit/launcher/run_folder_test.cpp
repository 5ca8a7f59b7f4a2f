// How `sensornet runs` classifies a run folder: live, finished (with its report's status) or
// unknown, from what was found in it; and what it shows of each.

#include "sensornet/launcher/run_folder.hpp"

#include <gtest/gtest.h>

#include "../../support/scratch_dir.hpp"

namespace sensornet::launcher {
namespace {

using nlohmann::json;

// A finished run's report as `sensornet runs` reads it.
report::RunRecord reportOf(report::RunStatus status, std::uint64_t episodes,
                           std::optional<std::uint64_t> planned = std::nullopt) {
  report::RunRecord run;
  run.run_id = "run-1";
  run.status = status;
  run.episodes = episodes;
  run.episodes_planned = planned;
  return run;
}

RunFolderFacts folder(const std::string& id) {
  RunFolderFacts facts;
  facts.folder = "/scratch/" + id;
  return facts;
}

const json kRecord = {{"run_id", "run-1"},      {"scenario", "/s/default.yaml"},
                      {"episodes", 20},         {"report", "/out/report.json"},
                      {"launcher_pid", 4242},   {"started_at", "2026-12-01T23:40:02Z"}};

TEST(RunFolder, AHeldLockIsALiveRunWhateverItsReportSays) {
  RunFolderFacts facts = folder("run-1");
  facts.record = kRecord;
  facts.lock = {true, true, std::nullopt};
  facts.episodes_logged = 3;
  facts.report = reportOf(report::RunStatus::Completed, 20);  // a stale report of an earlier run
  const RunEntry e = classifyRun(facts);
  EXPECT_EQ(e.state, RunState::Live);
  EXPECT_EQ(e.status, "live");
  EXPECT_EQ(e.episodes, 3);
  EXPECT_EQ(e.episodes_planned, 20);
  EXPECT_EQ(episodesText(e), "3/20");
}

TEST(RunFolder, WithoutALockTheLaunchersPidDecides) {
  RunFolderFacts facts = folder("run-1");
  facts.record = kRecord;
  facts.launcher_alive = true;
  EXPECT_TRUE(isLive(facts)) << "no lock file (an older launcher): its pid is alive";
  facts.lock.exists = true;  // a lock nobody holds: the launcher left, whatever has its pid now
  EXPECT_FALSE(isLive(facts));
  EXPECT_EQ(launcherPidOf(facts), 4242);
}

TEST(RunFolder, AReportWithAKnownStatusIsAFinishedRun) {
  RunFolderFacts facts = folder("run-1");
  facts.record = kRecord;
  facts.lock.exists = true;
  facts.report = reportOf(report::RunStatus::Degraded, 17, 18);
  const RunEntry e = classifyRun(facts);
  EXPECT_EQ(e.state, RunState::Finished);
  EXPECT_EQ(e.status, "degraded");
  EXPECT_EQ(e.episodes, 17);
  EXPECT_EQ(e.episodes_planned, 18) << "the report's plan wins over run.json's";
  EXPECT_EQ(e.report, "/out/report.json") << "run.json names the report";
  EXPECT_EQ(e.scenario, "/s/default.yaml");
  EXPECT_EQ(e.started_at, "2026-12-01T23:40:02Z");
}

TEST(RunFolder, AReportWithoutAKnownStatusOrNoReportIsUnknown) {
  RunFolderFacts facts = folder("run-2");
  EXPECT_EQ(classifyRun(facts).state, RunState::Unknown);
  EXPECT_EQ(classifyRun(facts).status, "unknown");
  // A report of a status this version does not know is no report it reads: unknown.
  testing::ScratchDir dir;
  const json base = {{"run_id", "run-2"}, {"summary", json::object()}, {"episodes", 4}};
  for (const json& status : {json("splendid"), json(3)}) {
    json doc = base;
    doc["status"] = status;
    facts.report = finishedReportAt(dir.write("report.json", doc.dump()));
    EXPECT_FALSE(facts.report.has_value()) << doc.dump();
    EXPECT_EQ(classifyRun(facts).state, RunState::Unknown);
  }
  json known = base;
  known["status"] = "failed";
  const auto read = finishedReportAt(dir.write("report.json", known.dump()));
  ASSERT_TRUE(read.has_value());
  EXPECT_EQ(read->status, report::RunStatus::Failed);
  EXPECT_EQ(read->episodes, 4U);
}

TEST(RunFolder, WithoutARecordTheFolderNamesTheRunAndItsReport) {
  RunFolderFacts facts = folder("run-3");
  facts.lock = {true, false, std::time_t{0}};
  const RunEntry e = classifyRun(facts);
  EXPECT_EQ(e.run_id, "run-3");
  EXPECT_EQ(e.report, "/scratch/run-3/report.json");
  EXPECT_EQ(e.launcher_pid, 0);
  EXPECT_EQ(e.started_at, "1970-01-01T00:00:00Z") << "the lock's time when run.json has none";
  EXPECT_EQ(episodesText(e), "-");
}

TEST(RunFolder, RunsAreSortedByStartThenIdWithUnknownStartsLast) {
  std::vector<RunEntry> runs(4);
  runs[0].run_id = "d";
  runs[1].run_id = "c";
  runs[1].started_at = "2026-12-02T00:00:00Z";
  runs[2].run_id = "b";
  runs[2].started_at = "2026-12-01T00:00:00Z";
  runs[3].run_id = "a";
  runs[3].started_at = "2026-12-02T00:00:00Z";
  sortRuns(runs);
  std::vector<std::string> ids;
  for (const RunEntry& e : runs) ids.push_back(e.run_id);
  EXPECT_EQ(ids, (std::vector<std::string>{"b", "a", "c", "d"}));
}

TEST(RunFolder, JsonSaysUnknownsAsNullAndTheStatusOfFinishedRunsOnly) {
  RunFolderFacts facts = folder("run-4");
  facts.record = kRecord;
  facts.launcher_alive = true;
  const json live = runEntryJson(classifyRun(facts));
  EXPECT_EQ(live["state"], "live");
  EXPECT_TRUE(live["status"].is_null());
  EXPECT_TRUE(live["episodes"].is_null());
  EXPECT_EQ(live["episodes_planned"], 20);
  EXPECT_EQ(live["folder"], "/scratch/run-4");
}

TEST(RunFolder, TheTableLinesUpItsColumns) {
  RunEntry e;
  e.run_id = "run-12";
  e.status = "completed";
  const std::string table = runsTable({e});
  EXPECT_EQ(table,
            "RUN     STATUS     STARTED  EPISODES  SCENARIO\n"
            "run-12  completed  -        -         -\n");
}

TEST(RunFolder, TheRecordReadsBackAsTheLauncherWroteIt) {
  const LaunchRecord record{"run-5", "/s/x.yaml", 7, "/r/report.json", 99, "2026-12-05T12:00:00Z"};
  RunFolderFacts facts = folder("run-5");
  facts.record = launchRecordJson(record);
  facts.lock.exists = true;
  const RunEntry e = classifyRun(facts);
  EXPECT_EQ(e.scenario, "/s/x.yaml");
  EXPECT_EQ(e.episodes_planned, 7);
  EXPECT_EQ(e.report, "/r/report.json");
  EXPECT_EQ(e.launcher_pid, 99);
  EXPECT_EQ(e.started_at, "2026-12-05T12:00:00Z");
}

}  // namespace
}  // namespace sensornet::launcher
