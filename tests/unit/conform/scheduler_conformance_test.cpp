// The rules of a scheduler's role (checkScheduler) on made-up runs: two commands, each written,
// left unanswered once (the coordinator's --drop-first-command-copy), written again 2 s later
// and answered, pass every rule; each way of breaking one rule fails that rule and no other.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "sensornet/conform/sensor_conformance.hpp"
#include "sensornet/core/scenario.hpp"

namespace sensornet::conform {
namespace {

constexpr std::int64_t kSecond = 1'000'000'000;
constexpr std::int64_t kT0 = 1'700'000'000LL * kSecond;
const std::string kRun = "sched";
const std::string kOperator = "sensornet/sched/operator";

class SchedulerConformanceTest : public ::testing::Test {
 protected:
  SchedulerConformanceTest() {
    run_.run_id = kRun;
    run_.first_ns = kT0;
    emulator::CommandEvent replan;
    replan.run_id = kRun;
    replan.command_id = 11;
    replan.kind = emulator::CommandKind::Replan;
    replan.surrogate = "info";
    replan.issuer = "my scheduler";
    emulator::CommandEvent budget = replan;
    budget.command_id = 12;
    budget.kind = emulator::CommandKind::SetBudget;
    budget.surrogate.clear();
    budget.budget = {8.0, 4.0};
    // Each: a copy at t, another at t + 2 s, the reply 5 ms later.
    for (const auto& [command, kind, at] :
         {std::tuple{replan, "COMMAND_REPLAN", 3 * kSecond},
          std::tuple{budget, "COMMAND_SET_BUDGET", 9 * kSecond}}) {
      run_.commands.push_back({command, kind, kOperator, kT0 + at});
      run_.commands.push_back({command, kind, kOperator, kT0 + at + 2 * kSecond});
      run_.replies.push_back(
          {command.command_id, true, 2, "re-planned", kT0 + at + 2 * kSecond + kSecond / 200});
    }
    report::RunRecord record;
    record.status = emulator::RunStatus::Completed;
    facts_.launcher_exit = 0;
    facts_.report = record;
    facts_.program_exit = 0;
    facts_.program_end = "exited with status 0";
  }

  void expectOnlyFails(const std::string& rule) const {
    std::vector<std::string> failing;
    for (const RuleCheck& r : checkScheduler(run_, facts_)) {
      if (!r.pass) failing.push_back(r.rule + ": " + r.evidence);
    }
    ASSERT_EQ(failing.size(), 1u) << ::testing::PrintToString(failing);
    EXPECT_EQ(failing[0].rfind(rule + ":", 0), 0u) << failing[0];
  }

  RecordedRun run_;
  RunFacts facts_;
};

TEST_F(SchedulerConformanceTest, CommandsResentUntilAnsweredPassEveryRule) {
  const std::vector<RuleCheck> rules = checkScheduler(run_, facts_);
  ASSERT_EQ(rules.size(), 8u);
  for (const RuleCheck& r : rules) EXPECT_TRUE(r.pass) << r.rule << ": " << r.evidence;
  EXPECT_EQ(rules[0].evidence.rfind("2 commands (1 COMMAND_REPLAN, 1 COMMAND_SET_BUDGET)", 0), 0u)
      << rules[0].evidence;
}

TEST_F(SchedulerConformanceTest, ARecorderThatMissedTheFirstCopyStillSeesTheRetryByItsReply) {
  run_.commands.erase(run_.commands.begin());  // only the second copy of command 11
  const std::vector<RuleCheck> rules = checkScheduler(run_, facts_);
  for (const RuleCheck& r : rules) EXPECT_TRUE(r.pass) << r.rule << ": " << r.evidence;
}

TEST_F(SchedulerConformanceTest, NoCommandFailsTheCommandsAndWhatNeedsOne) {
  run_.commands.clear();
  run_.replies.clear();
  std::vector<std::string> failing;
  for (const RuleCheck& r : checkScheduler(run_, facts_)) {
    if (!r.pass) failing.push_back(r.rule);
  }
  // Nothing to judge is no pass: every rule about commands fails, leaving and the run do not.
  EXPECT_EQ(failing, (std::vector<std::string>{"commands", "by-right", "command-ids", "retries",
                                               "replies-read", "accepted"}));
}

TEST_F(SchedulerConformanceTest, ACommandInAnotherPartitionOrOfTheLaunchersKindFailsByRight) {
  run_.commands[2].partition = run_.commands[3].partition = "sensornet/sched/launcher";
  run_.replies[1].reason = "not permitted: only the launcher may ...";
  run_.replies[1].accepted = false;
  expectOnlyFails("by-right");  // the refusal is by-right's to tell, not `accepted`'s
  run_.commands[2].partition = run_.commands[3].partition = "sensornet/sched";
  run_.replies[1] = {12, true, 2, "", run_.replies[1].written_ns};
  expectOnlyFails("by-right");  // heard by nobody, but recorded
  run_.commands[2].partition = run_.commands[3].partition = kOperator;
  run_.commands[2].command.kind = run_.commands[3].command.kind =
      emulator::CommandKind::SensorsFailed;
  expectOnlyFails("by-right");
}

TEST_F(SchedulerConformanceTest, TheLaunchersOwnFailureNoticeIsNotTheSchedulers) {
  RecordedCommand notice = run_.commands[0];
  notice.command.command_id = 99;
  notice.command.kind = emulator::CommandKind::SensorsFailed;
  notice.command.issuer = "sensornet launch 4242";
  notice.partition = "sensornet/sched/launcher";
  run_.commands.push_back(notice);  // once, unanswered: it would fail retries were it judged
  for (const RuleCheck& r : checkScheduler(run_, facts_)) {
    EXPECT_TRUE(r.pass) << r.rule << ": " << r.evidence;
  }
}

TEST_F(SchedulerConformanceTest, AnIdReusedForAnotherCommandOrAnotherRunFailsCommandIds) {
  run_.commands[3].command.surrogate = "cov";  // command 12's second copy asks something else
  expectOnlyFails("command-ids");
  run_.commands[3].command.surrogate.clear();
  run_.commands[2].command.run_id = run_.commands[3].command.run_id = "other";
  expectOnlyFails("command-ids");
}

TEST_F(SchedulerConformanceTest, ACommandWrittenOnceAndNeverAgainFailsRetries) {
  run_.commands.erase(run_.commands.begin() + 3);  // command 12: the first copy alone
  run_.replies.pop_back();                         // so no reply
  // With no reply, nothing is to be read or accepted for it; command 11 still is.
  expectOnlyFails("retries");
}

TEST_F(SchedulerConformanceTest, AResendTooSoonOrTooLateFailsRetries) {
  run_.commands[1].written_ns = run_.commands[0].written_ns + kSecond / 10;
  run_.replies[0].written_ns = run_.commands[1].written_ns + kSecond / 200;
  expectOnlyFails("retries");
  run_.commands[1].written_ns = run_.commands[0].written_ns + 4 * kSecond;
  run_.replies[0].written_ns = run_.commands[1].written_ns + kSecond / 200;
  expectOnlyFails("retries");
}

TEST_F(SchedulerConformanceTest, CopiesAfterTheReplyFailRepliesRead) {
  RecordedCommand again = run_.commands[1];
  again.written_ns = run_.replies[0].written_ns + 2 * kSecond;
  run_.commands.insert(run_.commands.begin() + 2, again);
  expectOnlyFails("replies-read");
  // One crossing its reply on the wire is no fault.
  run_.commands[2].written_ns = run_.replies[0].written_ns + kSecond / 10;
  for (const RuleCheck& r : checkScheduler(run_, facts_)) {
    EXPECT_TRUE(r.pass) << r.rule << ": " << r.evidence;
  }
}

TEST_F(SchedulerConformanceTest, ARefusedCommandFailsAccepted) {
  run_.replies[1].accepted = false;
  run_.replies[1].reason = "budget must hold 2 finite values > 0";
  expectOnlyFails("accepted");
}

TEST_F(SchedulerConformanceTest, StayingAfterTheRunOrFailingFailsLeaving) {
  facts_.program_exit.reset();
  facts_.program_end = "was still running 5 s after the run ended: stopped";
  expectOnlyFails("leaving");
  facts_.program_exit = 3;
  expectOnlyFails("leaving");
}

TEST_F(SchedulerConformanceTest, ARunThatDidNotCompleteFailsTheRun) {
  facts_.launcher_exit = 1;
  facts_.report->status = emulator::RunStatus::Failed;
  expectOnlyFails("run");
}

}  // namespace
}  // namespace sensornet::conform
