// Which run `watch` and `status` look at without --run-id: the one live run, never one picked
// out of several (another person's run under the same account), and why when there is none.

#include "sensornet/launcher/run_choice.hpp"

#include <gtest/gtest.h>

namespace sensornet::launcher {
namespace {

LiveRun live(const std::string& id, pid_t pid) {
  return {id, pid, std::nullopt, "/tmp/s/" + id, "23:10:05"};
}

TEST(RunChoice, TakesTheOneLiveRun) {
  const RunChoice choice = chooseRun("", std::nullopt, {live("run-a", 10)}, "/rec");
  ASSERT_TRUE(choice.run.has_value()) << choice.expected;
  EXPECT_EQ(choice.run->run_id, "run-a");
}

TEST(RunChoice, TheRecordAndTheScratchFolderNamingOneRunAreOneRun) {
  const RecordedRun record{{"run-a", 10, 7, "", ""}, true};
  const RunChoice choice = chooseRun("", record, {live("run-a", 10)}, "/rec");
  ASSERT_TRUE(choice.run.has_value()) << choice.expected;
  EXPECT_EQ(choice.run->domain_id, std::optional<int>(7)) << "the record knows the domain";
}

TEST(RunChoice, SeveralLiveRunsAreListedAndNoneIsPicked) {
  const RecordedRun record{{"run-b", 20, std::nullopt, "", ""}, true};
  const RunChoice choice = chooseRun("", record, {live("run-a", 10), live("run-c", 30)}, "/rec");
  EXPECT_FALSE(choice.run.has_value());
  EXPECT_NE(choice.expected.find("3 runs are live on this host"), std::string::npos)
      << choice.expected;
  for (const char* id : {"run-a (launcher pid 10, started 23:10:05, logs in /tmp/s/run-a)",
                         "run-b (launcher pid 20)", "run-c (launcher pid 30"}) {
    EXPECT_NE(choice.expected.find(id), std::string::npos) << choice.expected;
  }
}

TEST(RunChoice, AGivenRunIdIsTakenAsGiven) {
  const RunChoice choice =
      chooseRun("run-x", std::nullopt, {live("run-a", 10), live("run-b", 2)}, "/r");
  ASSERT_TRUE(choice.run.has_value());
  EXPECT_EQ(choice.run->run_id, "run-x");
}

TEST(RunChoice, AStaleRecordSaysTheRunIsOver) {
  const RecordedRun record{{"run-a", 10, std::nullopt, "", ""}, false};
  const RunChoice choice = chooseRun("", record, {}, "/rec");
  EXPECT_FALSE(choice.run.has_value());
  EXPECT_NE(choice.expected.find("run-a, is over (its launcher, pid 10, is gone)"),
            std::string::npos)
      << choice.expected;
}

TEST(RunChoice, NoRecordAndNoRunNamesTheRecord) {
  const RunChoice choice = chooseRun("", std::nullopt, {}, "/run/user/1/sensornet/current-run");
  EXPECT_FALSE(choice.run.has_value());
  EXPECT_NE(choice.expected.find("(no /run/user/1/sensornet/current-run)"), std::string::npos)
      << choice.expected;
}

// A stale record and one run in the scratch folder: that run.
TEST(RunChoice, ALiveRunInTheScratchFolderOutranksAStaleRecord) {
  const RecordedRun record{{"run-old", 10, std::nullopt, "", ""}, false};
  const RunChoice choice = chooseRun("", record, {live("run-new", 11)}, "/rec");
  ASSERT_TRUE(choice.run.has_value()) << choice.expected;
  EXPECT_EQ(choice.run->run_id, "run-new");
}

}  // namespace
}  // namespace sensornet::launcher
