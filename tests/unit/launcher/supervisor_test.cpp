// The launcher's supervisor core driven by scripted orders of events with a fake clock: what it
// restarts, whom it tells that sensors failed, when it stops the run, which faults it records.
// Expectations come from docs/guide/faults.md's fault response and docs/ARCHITECTURE.md's outcome table (restart a
// killed coordinator or fusion center at most 3 times; a sensor death is survived under replan
// and continue and ends the run under stop; a child ended by the launcher's own stop is no
// fault), never from the program's output.

#include "sensornet/launcher/supervisor.hpp"

#include <gtest/gtest.h>

#include <csignal>
#include <variant>

#include "sensornet/launcher/run_verdict.hpp"

namespace sensornet::launcher {
namespace {

using emulator::FaultKind;
using emulator::RunStatus;
using emulator::FailurePolicy;
using std::chrono::milliseconds;
using std::chrono::seconds;

const SteadyTime kStart{};  // the fake clock's zero

SupervisorConfig twoAgents(FailurePolicy policy = FailurePolicy::Replan) {
  SupervisorConfig config;
  config.sensor_agents = {{"sensor_agent-0-2", {0, 1, 2}}, {"sensor_agent-3-5", {3, 4, 5}}};
  config.on_sensor_failure = policy;
  return config;
}

ChildExit exited(const std::string& name, int status, pid_t pid = 100) {
  return {name, pid, status, 0};
}
ChildExit killed(const std::string& name, int signal = SIGKILL, pid_t pid = 100) {
  return {name, pid, 128 + signal, signal};
}
RunPosition episode(std::uint32_t k, double t = 0.5) { return {k, t}; }

template <class A>
int count(const std::vector<Action>& actions) {
  int n = 0;
  for (const Action& a : actions) n += std::holds_alternative<A>(a) ? 1 : 0;
  return n;
}
template <class A>
const A* first(const std::vector<Action>& actions) {
  for (const Action& a : actions) {
    if (const A* found = std::get_if<A>(&a)) return found;
  }
  return nullptr;
}

// The verdict of a run the fusion center reported as `reported` with every episode finished.
Verdict verdictOf(const Supervisor& s, const std::string& reported = "completed") {
  ReportSeen seen;
  seen.readable = true;
  seen.status = reported;
  seen.finished_episodes = 20;
  return decideVerdict(s.faults(), s.interrupted(), seen, 20);
}

// The run ends in order and by itself: coordinator, fusion center, sensor agents.
void endNormally(Supervisor& s, SteadyTime now) {
  (void)s.onChildExit(exited(kCoordinator, 0), {}, now);
  (void)s.onChildExit(exited(kFusionCenter, 0), {}, now);
  (void)s.onChildExit(exited("sensor_agent-0-2", 0), {}, now);
  (void)s.onChildExit(exited("sensor_agent-3-5", 0), {}, now);
}

TEST(Supervisor, CleanRunEndsWithoutFaultsAndCompletes) {
  Supervisor s(twoAgents(), kStart);
  EXPECT_FALSE(s.done());
  endNormally(s, kStart + seconds(10));
  EXPECT_TRUE(s.done());
  EXPECT_TRUE(s.faults().empty());
  EXPECT_FALSE(s.failure());
  const Verdict v = verdictOf(s);
  EXPECT_EQ(v.status, RunStatus::Completed);
  EXPECT_EQ(exitCodeOf(v.status), 0);
}

TEST(Supervisor, FusionCenterKilledTwiceRecordsBothRestarts) {
  Supervisor s(twoAgents(), kStart);
  const auto a1 = s.onChildExit(killed(kFusionCenter, SIGKILL, 201), episode(2), kStart);
  ASSERT_EQ(count<RestartChild>(a1), 1);
  EXPECT_EQ(first<RestartChild>(a1)->attempt, 1);
  (void)s.onRestarted(kFusionCenter, 301, "fusion_center.restart-1.log");
  const auto a2 = s.onChildExit(killed(kFusionCenter, SIGKILL, 301), episode(4), kStart);
  ASSERT_EQ(count<RestartChild>(a2), 1);
  EXPECT_EQ(first<RestartChild>(a2)->attempt, 2);
  (void)s.onRestarted(kFusionCenter, 302, "fusion_center.restart-2.log");
  EXPECT_EQ(count<StopRun>(a1) + count<StopRun>(a2), 0);

  const std::vector<Fault> faults = s.faults();
  ASSERT_EQ(faults.size(), 2u) << "one fault per death, both kept (issue 31, item 5)";
  for (const Fault& f : faults) {
    EXPECT_EQ(f.kind, FaultKind::ProcessKilled);
    EXPECT_EQ(f.process, kFusionCenter);
    EXPECT_TRUE(f.survived);
  }
  EXPECT_EQ(faults[0].at.episode, 2u);
  EXPECT_EQ(faults[1].at.episode, 4u);
  EXPECT_NE(faults[0].detail.find("restart 1 of 3, pid 301"), std::string::npos)
      << faults[0].detail;
  EXPECT_NE(faults[1].detail.find("restart 2 of 3, pid 302"), std::string::npos)
      << faults[1].detail;
  endNormally(s, kStart);
  const Verdict v = verdictOf(s);
  EXPECT_EQ(v.status, RunStatus::Degraded);
  EXPECT_EQ(exitCodeOf(v.status), 3);
}

// Issue 31, finding 4: the launcher was stopped (SIGSTOP) from 0.33 s into episode 0 while a
// sensor agent died, and found it dead only when it ran again, in episode 1 at 0.95 s. The death
// is dated by the last sight of the agent alive (episode 0 at 0.33 s), not by the moment the
// launcher found it, and the fault and the failure notice say when it was found.
TEST(Supervisor, ADeathFoundLateIsDatedByTheLastSightOfTheChildAlive) {
  Supervisor s(twoAgents(), kStart);
  const LastSeenAlive seen{episode(0, 0.33), 2.1};
  const auto actions = s.onChildExit(killed("sensor_agent-0-2"), episode(1, 0.95), kStart, seen);
  ASSERT_EQ(count<NotifySensorsFailed>(actions), 1);
  const std::vector<Fault> faults = s.faults();  // a copy: a reference into it would dangle
  ASSERT_EQ(faults.size(), 1u);
  const Fault& f = faults[0];
  EXPECT_EQ(f.at.episode, 0u) << "it died in episode 0, before episode 1 began";
  ASSERT_TRUE(f.at.emulated_time_s.has_value());
  EXPECT_DOUBLE_EQ(*f.at.emulated_time_s, 0.33);
  EXPECT_NE(f.detail.find("died after episode 0 at t = 0.33 s (last seen alive then), found dead "
                          "2.1 s later, episode 1 at t = 0.95 s"),
            std::string::npos)
      << f.detail;
  EXPECT_NE(first<NotifySensorsFailed>(actions)->detail.find("died after episode 0"),
            std::string::npos);
}

// Seen alive one watch step before it was found dead: dated where it was found, as always.
TEST(Supervisor, ADeathFoundAtOnceIsDatedWhereItWasFound) {
  Supervisor s(twoAgents(), kStart);
  const LastSeenAlive seen{episode(1, 0.90), 0.05};
  (void)s.onChildExit(killed("sensor_agent-0-2"), episode(1, 0.95), kStart, seen);
  ASSERT_EQ(s.faults().size(), 1u);
  EXPECT_EQ(s.faults()[0].at.episode, 1u);
  EXPECT_DOUBLE_EQ(s.faults()[0].at.emulated_time_s.value_or(0.0), 0.95);
  EXPECT_EQ(s.faults()[0].detail.find("died after"), std::string::npos) << s.faults()[0].detail;
}

TEST(Supervisor, FusionCenterKilledOnceTooOftenFailsTheRun) {
  Supervisor s(twoAgents(), kStart);
  for (int k = 1; k <= 3; ++k) {
    ASSERT_EQ(count<RestartChild>(s.onChildExit(killed(kFusionCenter), episode(1), kStart)), 1);
    (void)s.onRestarted(kFusionCenter, 300 + k, "log");
  }
  const auto last = s.onChildExit(killed(kFusionCenter), episode(2), kStart);
  EXPECT_EQ(count<RestartChild>(last), 0);
  EXPECT_EQ(count<StopRun>(last), 1);
  ASSERT_EQ(s.faults().size(), 4u);
  EXPECT_FALSE(s.faults().back().survived);
  EXPECT_EQ(verdictOf(s).status, RunStatus::Failed);
}

TEST(Supervisor, CoordinatorThatExitsOnItsOwnFailsTheRunWithoutRestart) {
  Supervisor s(twoAgents(), kStart);
  const auto actions = s.onChildExit(exited(kCoordinator, 1), episode(3), kStart);
  EXPECT_EQ(count<RestartChild>(actions), 0);
  EXPECT_EQ(count<StopRun>(actions), 1);
  ASSERT_EQ(s.faults().size(), 1u);
  EXPECT_EQ(s.faults()[0].kind, FaultKind::ProcessFailed);
  EXPECT_EQ(exitCodeOf(verdictOf(s).status), 1);
}

TEST(Supervisor, KilledCoordinatorIsRestarted) {
  Supervisor s(twoAgents(), kStart);
  const auto actions = s.onChildExit(killed(kCoordinator), episode(3), kStart);
  ASSERT_EQ(count<RestartChild>(actions), 1);
  EXPECT_EQ(first<RestartChild>(actions)->name, kCoordinator);
  EXPECT_EQ(count<StopRun>(actions), 0);
  (void)s.onRestarted(kCoordinator, 400, "coordinator.restart-1.log");
  endNormally(s, kStart);
  EXPECT_EQ(verdictOf(s).status, RunStatus::Degraded);
}

TEST(Supervisor, RestartThatCannotStartFailsTheRun) {
  Supervisor s(twoAgents(), kStart);
  (void)s.onChildExit(killed(kCoordinator), episode(1), kStart);
  const auto actions = s.onRestartFailed(kCoordinator, "no such program");
  EXPECT_EQ(count<StopRun>(actions), 1);
  ASSERT_EQ(s.faults().size(), 1u);
  EXPECT_FALSE(s.faults()[0].survived);
  EXPECT_EQ(verdictOf(s).status, RunStatus::Failed);
}

TEST(Supervisor, CtrlCStopsTheRunAndEndsItInterrupted) {
  Supervisor s(twoAgents(), kStart);
  const auto actions = s.onSignal(SIGINT, episode(2, 1.25));
  EXPECT_EQ(count<StopRun>(actions), 1);
  EXPECT_FALSE(s.done()) << "done once the stop is carried out";
  EXPECT_TRUE(s.onSignal(SIGINT, episode(2)).empty()) << "a second Ctrl-C while stopping";
  s.onStopped();
  EXPECT_TRUE(s.done());
  ASSERT_EQ(s.faults().size(), 1u);
  EXPECT_EQ(s.faults()[0].kind, FaultKind::Interrupted);
  EXPECT_EQ(s.faults()[0].process, kLauncherProcess);
  EXPECT_EQ(s.faults()[0].detail, "interrupted by SIGINT");
  EXPECT_EQ(s.faults()[0].at.episode, 2u);
  const Verdict v = verdictOf(s, "interrupted");
  EXPECT_EQ(v.status, RunStatus::Interrupted);
  EXPECT_EQ(exitCodeOf(v.status), 1);
}

TEST(Supervisor, ChildrenEndedByTheStopAreNotFaults) {
  Supervisor s(twoAgents(), kStart);
  (void)s.onSignal(SIGTERM, episode(2));
  // What the stop makes of them, whatever their status: consequences of the interrupt.
  for (const ChildExit& e : {exited(kCoordinator, 1), killed("sensor_agent-0-2", SIGKILL),
                             killed("sensor_agent-3-5", SIGTERM), exited(kFusionCenter, 2)}) {
    const auto actions = s.onChildExit(e, episode(2), kStart + seconds(1));
    EXPECT_EQ(count<RestartChild>(actions) + count<NotifySensorsFailed>(actions), 0) << e.name;
  }
  s.onStopped();
  ASSERT_EQ(s.faults().size(), 1u);
  EXPECT_EQ(s.faults()[0].kind, FaultKind::Interrupted);
  EXPECT_EQ(s.failure()->kind, RunFailureKind::Interrupted);
}

TEST(Supervisor, ChildThatDiesWhileTheRunIsStoppedAfterAFailureIsNoSecondFault) {
  Supervisor s(twoAgents(), kStart);
  ASSERT_EQ(count<StopRun>(s.onChildExit(exited(kCoordinator, 1), episode(1), kStart)), 1);
  (void)s.onChildExit(killed("sensor_agent-0-2", SIGKILL), episode(1), kStart);
  (void)s.onChildExit(exited(kFusionCenter, 1), episode(1), kStart);
  s.onStopped();
  ASSERT_EQ(s.faults().size(), 1u);
  EXPECT_EQ(s.faults()[0].process, kCoordinator);
  EXPECT_EQ(s.failure()->child, kCoordinator);
}

// The death of a sensor agent mid-run under a policy the run survives.
void expectSurvivedDeath(FailurePolicy policy) {
  Supervisor s(twoAgents(policy), kStart);
  const auto actions = s.onChildExit(killed("sensor_agent-3-5"), episode(2, 0.75), kStart);
  ASSERT_EQ(count<NotifySensorsFailed>(actions), 1);
  EXPECT_EQ(first<NotifySensorsFailed>(actions)->sensors, (std::vector<int>{3, 4, 5}));
  EXPECT_EQ(count<StopRun>(actions), 0);
  EXPECT_EQ(count<RestartChild>(actions), 0);
  s.onReply("sensor_agent-3-5", {true, 3, "policy " + std::string(wordOf(policy))});
  (void)s.onChildExit(exited(kCoordinator, 0), {}, kStart);
  (void)s.onChildExit(exited(kFusionCenter, 0), {}, kStart);
  (void)s.onChildExit(exited("sensor_agent-0-2", 0), {}, kStart);
  EXPECT_TRUE(s.done()) << "the dead agent is not waited for";
  ASSERT_EQ(s.faults().size(), 1u);
  const std::vector<Fault> faults = s.faults();
  const Fault& f = faults[0];
  EXPECT_TRUE(f.survived);
  EXPECT_EQ(f.kind, FaultKind::ProcessKilled);
  EXPECT_EQ(f.sensors, (std::vector<int>{3, 4, 5}));
  EXPECT_EQ(f.schedule_version, 3u);
  EXPECT_NE(f.detail.find("policy " + std::string(wordOf(policy))), std::string::npos);
  const Verdict v = verdictOf(s, "degraded");
  EXPECT_EQ(v.status, RunStatus::Degraded);
  EXPECT_EQ(exitCodeOf(v.status), 3);
}

TEST(Supervisor, SensorDeathUnderReplanIsSurvived) {
  expectSurvivedDeath(FailurePolicy::Replan);
}
TEST(Supervisor, SensorDeathUnderContinueIsSurvived) {
  expectSurvivedDeath(FailurePolicy::Continue);
}

TEST(Supervisor, SensorDeathUnderStopIsTheOneCauseOfTheFailedRun) {
  Supervisor s(twoAgents(FailurePolicy::Stop), kStart);
  const auto actions = s.onChildExit(killed("sensor_agent-0-2"), episode(1, 0.2), kStart);
  ASSERT_EQ(count<NotifySensorsFailed>(actions), 1);
  EXPECT_EQ(count<StopRun>(actions), 0) << "the coordinator ends the run, the launcher waits";
  s.onReply("sensor_agent-0-2", {true, 0, "policy stop: the run ends"});
  // The coordinator was told to stop: exit 1 today, 0 once it exits cleanly; either way no fault.
  EXPECT_TRUE(s.onChildExit(exited(kCoordinator, 1), {}, kStart + seconds(1)).empty());
  (void)s.onChildExit(exited(kFusionCenter, 0), {}, kStart + seconds(2));
  (void)s.onChildExit(exited("sensor_agent-3-5", 0), {}, kStart + seconds(2));
  EXPECT_TRUE(s.done());
  ASSERT_EQ(s.faults().size(), 1u) << "one cause, one fault";
  const std::vector<Fault> faults = s.faults();
  const Fault& f = faults[0];
  EXPECT_EQ(f.process, "sensor_agent-0-2");
  EXPECT_FALSE(f.survived);
  EXPECT_NE(f.detail.find("policy stop"), std::string::npos) << f.detail;
  EXPECT_NE(f.detail.find("the coordinator then ended the run (exited with status 1)"),
            std::string::npos)
      << f.detail;
  const Verdict v = verdictOf(s, "failed");
  EXPECT_EQ(v.status, RunStatus::Failed);
  EXPECT_EQ(exitCodeOf(v.status), 1);
  ASSERT_TRUE(s.failure());
  EXPECT_EQ(s.failure()->child, "sensor_agent-0-2");
}

TEST(Supervisor, LastSensorDeathEndsTheRunUnderAnyPolicy) {
  Supervisor s(twoAgents(FailurePolicy::Replan), kStart);
  (void)s.onChildExit(killed("sensor_agent-0-2"), episode(1), kStart);
  (void)s.onChildExit(killed("sensor_agent-3-5"), episode(2), kStart);
  EXPECT_TRUE(s.onChildExit(exited(kCoordinator, 1), {}, kStart).empty());
  (void)s.onChildExit(exited(kFusionCenter, 0), {}, kStart);
  EXPECT_TRUE(s.done());
  ASSERT_EQ(s.faults().size(), 2u);
  EXPECT_TRUE(s.faults()[0].survived);
  EXPECT_FALSE(s.faults()[1].survived) << "no sensor left: the run cannot go on";
  EXPECT_EQ(verdictOf(s, "failed").status, RunStatus::Failed);
}

TEST(Supervisor, ExternalSensorsThatLeaveMidRunAreADeathAnsweredOnce) {
  SupervisorConfig config = twoAgents(FailurePolicy::Replan);
  config.sensor_agents.pop_back();  // sensors 3..5: 3 ours, 4 and 5 a participant of the user's
  config.sensor_agents.push_back({"sensor_agent-3", {3}});
  config.external_sensors = {4, 5};
  Supervisor s(config, kStart);
  EXPECT_TRUE(s.onExternalSensorsGone({4, 5}, {}).empty()) << "before the first episode: not yet";
  const auto actions = s.onExternalSensorsGone({4, 5}, episode(2, 0.3));
  const auto* notice = first<NotifySensorsFailed>(actions);
  ASSERT_NE(notice, nullptr);
  EXPECT_EQ(notice->sensors, (std::vector<int>{4, 5}));
  EXPECT_EQ(notice->process, kExternalProcess);
  EXPECT_EQ(count<StopRun>(actions), 0);
  EXPECT_TRUE(s.onExternalSensorsGone({4, 5}, episode(2, 0.8)).empty()) << "answered once";
  s.onReply(kExternalProcess, {true, 3, "policy replan: version 3"});
  ASSERT_EQ(s.faults().size(), 1u);
  const Fault f = s.faults()[0];
  EXPECT_EQ(f.kind, FaultKind::SensorDied);
  EXPECT_EQ(f.sensors, (std::vector<int>{4, 5}));
  EXPECT_TRUE(f.survived);
  EXPECT_EQ(f.schedule_version, 3u);
  endNormally(s, kStart + seconds(1));  // waits for no external process
  (void)s.onChildExit(exited("sensor_agent-3", 0), {}, kStart + seconds(1));
  EXPECT_TRUE(s.done());
  EXPECT_EQ(verdictOf(s, "degraded").status, RunStatus::Degraded);
}

TEST(Supervisor, TheLastExternalSensorsLeavingWithEveryAgentDeadEndsTheRun) {
  SupervisorConfig config;
  config.sensor_agents = {{"sensor_agent-0", {0}}};
  config.external_sensors = {1};
  Supervisor s(config, kStart);
  (void)s.onChildExit(killed("sensor_agent-0"), episode(1), kStart);
  ASSERT_TRUE(s.faults()[0].survived) << "sensor 1 is still there";
  (void)s.onExternalSensorsGone({1}, episode(1, 0.9));
  ASSERT_EQ(s.faults().size(), 2u);
  EXPECT_FALSE(s.faults()[1].survived) << "no sensor left: the run cannot go on";
}

TEST(Supervisor, SensorAgentEndingBeforeTheFirstEpisodeFailsTheLaunch) {
  Supervisor s(twoAgents(), kStart);
  const auto actions = s.onChildExit(exited("sensor_agent-0-2", 2), {}, kStart);
  EXPECT_EQ(count<NotifySensorsFailed>(actions), 0);
  EXPECT_EQ(count<StopRun>(actions), 1);
  EXPECT_EQ(s.faults().at(0).kind, FaultKind::ProcessFailed);
  EXPECT_EQ(verdictOf(s).status, RunStatus::Failed);
}

// Killed before the first episode (kill -9 from outside, not a bad program): the failure policy
// answers it as any death, and the run that survives it is degraded, not failed.
TEST(Supervisor, SensorAgentKilledBeforeTheFirstEpisodeIsADeathThePolicyAnswers) {
  Supervisor s(twoAgents(FailurePolicy::Replan), kStart);
  const auto actions = s.onChildExit(killed("sensor_agent-3-5"), {}, kStart);
  ASSERT_EQ(count<NotifySensorsFailed>(actions), 1);
  EXPECT_EQ(first<NotifySensorsFailed>(actions)->sensors, (std::vector<int>{3, 4, 5}));
  EXPECT_EQ(count<StopRun>(actions), 0);
  s.onReply("sensor_agent-3-5", {true, 2, "policy replan"});
  (void)s.onChildExit(exited(kCoordinator, 0), {}, kStart);
  (void)s.onChildExit(exited(kFusionCenter, 0), {}, kStart);
  (void)s.onChildExit(exited("sensor_agent-0-2", 0), {}, kStart);
  EXPECT_TRUE(s.done());
  ASSERT_EQ(s.faults().size(), 1u);
  EXPECT_TRUE(s.faults()[0].survived);
  EXPECT_EQ(verdictOf(s, "degraded").status, RunStatus::Degraded);
}

TEST(Supervisor, ScriptedCrashIsNamedAsScripted) {
  SupervisorConfig config = twoAgents();
  config.scripted_crash_sensors = {4};
  Supervisor s(config, kStart);
  (void)s.onChildExit(killed("sensor_agent-3-5"), episode(2), kStart);
  ASSERT_EQ(s.faults().size(), 1u);
  EXPECT_EQ(s.faults()[0].kind, FaultKind::Crash);
  EXPECT_TRUE(s.faults()[0].survived);
}

TEST(Supervisor, UnansweredFailureNoticeIsSaid) {
  Supervisor s(twoAgents(), kStart);
  (void)s.onChildExit(killed("sensor_agent-0-2"), episode(1), kStart);
  EXPECT_NE(s.faults()[0].detail.find("did not answer the failure notice"), std::string::npos);
}

TEST(Supervisor, TimeoutStopsTheRunAtItsDeadline) {
  SupervisorConfig config = twoAgents();
  config.timeout = seconds(10);
  Supervisor s(config, kStart);
  EXPECT_TRUE(s.onTick(kStart + milliseconds(9'999), episode(5)).empty());
  const auto actions = s.onTick(kStart + seconds(10), episode(5));
  EXPECT_EQ(count<StopRun>(actions), 1);
  ASSERT_EQ(s.faults().size(), 1u);
  EXPECT_EQ(s.faults()[0].kind, FaultKind::Timeout);
  EXPECT_EQ(s.faults()[0].detail, "the run did not end within --timeout 10 s");
  EXPECT_EQ(s.failure()->kind, RunFailureKind::TimedOut);
  EXPECT_EQ(verdictOf(s).status, RunStatus::Failed);
}

TEST(Supervisor, FusionCenterThatDoesNotLeaveAfterTheRunIsHung) {
  Supervisor s(twoAgents(), kStart);
  (void)s.onChildExit(exited(kCoordinator, 0), {}, kStart);
  EXPECT_TRUE(s.onTick(kStart + milliseconds(14'999), {}).empty());
  const auto actions = s.onTick(kStart + seconds(15), {});
  EXPECT_EQ(count<StopRun>(actions), 1);
  ASSERT_EQ(s.faults().size(), 1u);
  EXPECT_EQ(s.faults()[0].kind, FaultKind::ProcessHung);
  EXPECT_EQ(s.faults()[0].process, kFusionCenter);
}

TEST(Supervisor, LingeringSensorAgentsEndTheWatchWithoutAFault) {
  Supervisor s(twoAgents(), kStart);
  (void)s.onChildExit(exited(kCoordinator, 0), {}, kStart);
  (void)s.onChildExit(exited(kFusionCenter, 0), {}, kStart + seconds(1));
  (void)s.onTick(kStart + milliseconds(5'999), {});
  EXPECT_FALSE(s.done());
  (void)s.onTick(kStart + seconds(6), {});
  EXPECT_TRUE(s.done());
  EXPECT_TRUE(s.faults().empty());
}

}  // namespace
}  // namespace sensornet::launcher
