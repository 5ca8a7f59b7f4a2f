// The coordinator's decisions without DDS (emulator::CoordinatorCore), driven by scripted events
// on a fake clock: episode pacing and the two-outstanding rule, readiness, the failure policy
// under replan, continue and stop, the switch moment of a live change, repeated commands, the
// journal and a resume after a kill between a journal write and its announcement, exit codes.
// Every expected time follows from the options below (lead, gap, margin, horizon), every expected
// episode and version from the script.

#include "sensornet/emulator/coordinator_core.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "sensornet/core/emulated_plant.hpp"
#include "sensornet/planning/planner.hpp"
#include "sensornet/core/surrogate.hpp"

#include "emulator_test_support.hpp"

namespace sensornet::emulator {
namespace {

using test::smallScenario;

constexpr std::int64_t kSecond = 1'000'000'000;
constexpr std::int64_t kMs = 1'000'000;
constexpr std::int64_t kT0 = 1'700'000'000 * kSecond;  // the fake clock's first reading

template <class A>
std::vector<A> only(const CoordinatorActions& actions) {
  std::vector<A> out;
  for (const CoordinatorAction& a : actions) {
    if (const A* x = std::get_if<A>(&a)) out.push_back(*x);
  }
  return out;
}

std::vector<EpisodeControl> controls(const CoordinatorActions& actions, ControlKind kind) {
  std::vector<EpisodeControl> out;
  for (const PublishControl& p : only<PublishControl>(actions)) {
    if (p.control.kind == kind) out.push_back(p.control);
  }
  return out;
}

std::vector<EpisodeControl> starts(const CoordinatorActions& actions) {
  return controls(actions, ControlKind::EpisodeStart);
}

class CoordinatorCoreTest : public ::testing::Test {
 protected:
  CoordinatorCoreTest() : run_{smallScenario(), "digest", 3} {
    config_.run_id = "run-a";
    config_.episodes = 6;
    config_.time_scale = 1.0;
    horizon_ns_ = static_cast<std::int64_t>(run_.scenario.horizon_s * 1e9);
  }

  // Version 1 planned with the information surrogate, nothing announced.
  CoordinatorJournal freshJournal() const {
    CoordinatorJournal journal = journalHeader(config_, run_.digest, run_.seed);
    journal.settings = initialSettings(run_.scenario, PlanSurrogate::Information);
    PlanRequest request;
    request.surrogate = PlanSurrogate::Information;
    ScheduleVersion v1;
    v1.version = 1;
    v1.schedule = planSchedule(run_.scenario, request).schedule;
    v1.surrogate = SurrogateKind::Information;
    v1.bracket = computeBracket(run_.scenario, v1.schedule);
    journal.versions.push_back(v1);
    return journal;
  }

  CoordinatorActions make(const CoordinatorJournal& journal) {
    core_ = std::make_unique<CoordinatorCore>(config_, run_, journal, [this] { return now_; });
    return core_->start(now_);
  }
  CoordinatorActions make() { return make(freshJournal()); }

  CoordinatorActions tickAt(std::int64_t at) {
    now_ = at;
    return core_->tick(now_);
  }

  void everySensorReady() {
    for (int j = 0; j < run_.scenario.sensorCount(); ++j) {
      (void)core_->onSensorStatus({j, SensorState::Ready, 1, ""}, now_);
    }
    core_->onFusionCenterMatched(true);
  }

  // Start, every peer ready at now_, settled: returns what the first running tick announced.
  CoordinatorActions startRunning() {
    (void)make();
    everySensorReady();
    (void)tickAt(now_);
    return tickAt(now_ + config_.settle.count());
  }

  CoordinatorActions report(std::uint32_t episode) {
    ReportEvent r;
    r.episode = episode;
    return core_->onReport(r, now_);
  }

  // From its rightful sender unless `sender` says otherwise: the launcher reports sensors
  // failed, an operator sends the rest.
  CoordinatorActions command(CommandKind kind, std::uint64_t id,
                             std::vector<std::uint32_t> sensors = {},
                             std::optional<CommandSender> sender = std::nullopt) {
    CommandEvent c;
    c.run_id = config_.run_id;
    c.command_id = id;
    c.kind = kind;
    c.sender = sender.value_or(kind == CommandKind::SensorsFailed ? CommandSender::Launcher
                                                                  : CommandSender::Operator);
    c.issuer = "test";
    c.sensor_ids = std::move(sensors);
    c.surrogate = "cov";
    c.detail = "killed by signal 9";
    return core_->onCommand(c, now_);
  }

  // A fused covariance of `episode` at emulated time `at_s` (P0 scaled down).
  void fused(std::uint32_t episode, double at_s) {
    const auto n = static_cast<std::uint32_t>(run_.scenario.stateDim());
    const Eigen::MatrixXd P = 0.3 * run_.scenario.plant.P0;
    FusionStateEvent s{episode, at_s, n, std::vector<double>(P.data(), P.data() + P.size())};
    (void)core_->onFusionState(s, now_);
  }

  CoordinatorConfig config_;
  CoordinatedRun run_;
  std::int64_t horizon_ns_ = 0;
  std::int64_t now_ = kT0;
  std::unique_ptr<CoordinatorCore> core_;
};

// ---- pacing --------------------------------------------------------------------------------

using CoordinatorPacing = CoordinatorCoreTest;

TEST_F(CoordinatorPacing, FirstEpisodeStartsALeadFromNowAndTheNextIsAnnouncedWithIt) {
  const std::int64_t ready_at = kT0;
  const CoordinatorActions first = startRunning();
  const std::vector<EpisodeControl> s = starts(first);
  ASSERT_EQ(s.size(), 2u) << "two outstanding: the running one and the next";
  const std::int64_t start0 = ready_at + config_.settle.count() + 200 * kMs;
  EXPECT_EQ(s[0].episode, 0u);
  EXPECT_EQ(s[0].start_wall_ns, start0);
  EXPECT_EQ(s[1].episode, 1u);
  EXPECT_EQ(s[1].start_wall_ns, start0 + horizon_ns_ + 2 * kMs);  // end of 0 plus the gap
  EXPECT_EQ(s[0].schedule_version, 1u);
  EXPECT_TRUE(s[0].failed_sensors.empty());
  EXPECT_EQ(s[0].episodes_planned, 6u);
}

TEST_F(CoordinatorPacing, AtMostTwoEpisodesAreOutstandingWhateverTheClock) {
  (void)startRunning();
  for (int k = 1; k <= 20; ++k) {  // well past both episodes' ends, no report
    EXPECT_TRUE(starts(tickAt(now_ + horizon_ns_ / 4)).empty()) << "tick " << k;
  }
}

TEST_F(CoordinatorPacing, AReportOutOfOrderWaitsForTheOldestThenBothFree) {
  const std::vector<EpisodeControl> first = starts(startRunning());
  const std::int64_t end1 = first[1].start_wall_ns + horizon_ns_;
  now_ = first[1].start_wall_ns + kSecond;  // episode 1 runs
  (void)report(1);
  EXPECT_TRUE(starts(tickAt(now_ + kMs)).empty()) << "episode 0 is still outstanding";
  (void)report(0);
  const std::vector<EpisodeControl> next = starts(tickAt(now_ + kMs));
  ASSERT_EQ(next.size(), 2u);
  EXPECT_EQ(next[0].episode, 2u);
  EXPECT_EQ(next[0].start_wall_ns, end1 + 2 * kMs);
  EXPECT_EQ(next[1].episode, 3u);
  EXPECT_EQ(next[1].start_wall_ns, end1 + 2 * kMs + horizon_ns_ + 2 * kMs);
}

TEST_F(CoordinatorPacing, AReportAfterTheEndStartsTheNextEpisodeAGapFromNow) {
  const std::vector<EpisodeControl> first = starts(startRunning());
  now_ = first[1].start_wall_ns + horizon_ns_ + 5 * kSecond;  // both ended long ago
  (void)report(0);
  const std::vector<EpisodeControl> next = starts(tickAt(now_));
  ASSERT_EQ(next.size(), 1u);
  EXPECT_EQ(next[0].episode, 2u);
  EXPECT_EQ(next[0].start_wall_ns, now_ + 2 * kMs);
}

TEST_F(CoordinatorPacing, TheLastReportEndsTheRunWithExitZeroAndASummary) {
  config_.episodes = 2;
  (void)startRunning();
  (void)report(0);
  EXPECT_TRUE(starts(tickAt(now_ + kMs)).empty()) << "only two episodes in the run";
  EXPECT_FALSE(core_->exitCode());
  (void)report(1);
  const CoordinatorActions end = tickAt(now_ + kMs);
  const std::vector<ShutDownRun> shutdown = only<ShutDownRun>(end);
  ASSERT_EQ(shutdown.size(), 1u);
  EXPECT_FALSE(shutdown[0].control.aborted);
  EXPECT_EQ(shutdown[0].control.episodes_planned, 2u) << "RUN_SHUTDOWN says how many ran";
  const std::vector<ExitProgram> exit = only<ExitProgram>(end);
  ASSERT_EQ(exit.size(), 1u);
  EXPECT_EQ(exit[0].exit_code, 0);
  ASSERT_TRUE(exit[0].summary);
  EXPECT_EQ(exit[0].summary->episodes, 2);
  EXPECT_EQ(core_->exitCode(), 0);
}

TEST_F(CoordinatorPacing, AReportOfAnEpisodeTheRunDoesNotHaveIsCountedAndIgnored) {
  (void)startRunning();
  EXPECT_TRUE(only<WriteJournal>(report(99)).empty());
  EXPECT_EQ(core_->rejectedSamples(), 1u);
  EXPECT_FALSE(only<WriteJournal>(report(0)).empty()) << "a real report is journaled";
  EXPECT_TRUE(only<WriteJournal>(report(0)).empty()) << "a replayed one is not";
}

// ---- readiness -----------------------------------------------------------------------------

using CoordinatorReadiness = CoordinatorCoreTest;

TEST_F(CoordinatorReadiness, WaitsForEverySensorWithAScheduleAndTheFusionCenter) {
  (void)make();
  const int m = run_.scenario.sensorCount();
  for (int j = 0; j + 1 < m; ++j) (void)core_->onSensorStatus({j, SensorState::Running, 1, ""}, now_);
  core_->onFusionCenterMatched(true);
  (void)core_->onSensorStatus({m - 1, SensorState::Ready, 0, ""}, now_);  // no schedule yet
  (void)core_->onSensorStatus({m - 1, SensorState::Starting, 1, ""}, now_);
  for (int k = 0; k < 10; ++k) EXPECT_TRUE(starts(tickAt(now_ + 100 * kMs)).empty());
  (void)core_->onSensorStatus({m - 1, SensorState::Excluded, 1, ""}, now_);
  EXPECT_TRUE(starts(tickAt(now_)).empty()) << "ready, then the discovery settles";
  EXPECT_TRUE(starts(tickAt(now_ + config_.settle.count() - 1)).empty());
  EXPECT_EQ(starts(tickAt(now_ + 1)).size(), 2u);
}

TEST_F(CoordinatorReadiness, WithoutTheFusionCenterNoEpisodeStarts) {
  (void)make();
  everySensorReady();
  core_->onFusionCenterMatched(false);
  for (int k = 0; k < 10; ++k) EXPECT_TRUE(starts(tickAt(now_ + kSecond)).empty());
}

TEST_F(CoordinatorReadiness, AFailedSensorIsNotWaitedFor) {
  config_.on_sensor_failure = FailurePolicy::Continue;
  (void)make();
  for (int j = 1; j < run_.scenario.sensorCount(); ++j) {
    (void)core_->onSensorStatus({j, SensorState::Ready, 1, ""}, now_);
  }
  core_->onFusionCenterMatched(true);
  EXPECT_TRUE(starts(tickAt(now_ + kMs)).empty()) << "sensor 0 has not said it is ready";
  (void)command(CommandKind::SensorsFailed, 5, {0});
  (void)tickAt(now_ + kMs);
  const std::vector<EpisodeControl> s = starts(tickAt(now_ + config_.settle.count()));
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0].failed_sensors, std::vector<std::uint32_t>{0});
}

TEST_F(CoordinatorReadiness, NotReadyInTimeExitsOneWithoutAShutdown) {
  (void)make();
  core_->onFusionCenterMatched(true);
  // Sensors 0 and 2 said they are ready; 1 and 3 (of the 4) never did: the line names them.
  (void)core_->onSensorStatus({0, SensorState::Ready, 1, ""}, now_);
  (void)core_->onSensorStatus({2, SensorState::Ready, 1, ""}, now_);
  EXPECT_TRUE(only<ExitProgram>(tickAt(kT0 + 30 * kSecond)).empty()) << "the limit itself is in";
  const CoordinatorActions late = tickAt(kT0 + 30 * kSecond + 1);
  EXPECT_TRUE(only<ShutDownRun>(late).empty());
  ASSERT_EQ(only<ExitProgram>(late).size(), 1u);
  EXPECT_EQ(core_->exitCode(), kCoordinatorExitFailed);
  bool named = false;
  for (const LogLine& line : only<LogLine>(late)) {
    named |= line.text.find("2 of 4 sensors ready (not ready: sensors 1,3)") != std::string::npos;
  }
  EXPECT_TRUE(named) << "the sensors that never said they are ready are named";
}

TEST_F(CoordinatorReadiness, AStatusOfASensorTheScenarioDoesNotHaveIsCountedAndIgnored) {
  (void)make();
  (void)core_->onSensorStatus({run_.scenario.sensorCount(), SensorState::Ready, 1, ""}, now_);
  (void)core_->onSensorStatus({-1, SensorState::Ready, 1, ""}, now_);
  EXPECT_EQ(core_->rejectedSamples(), 2u);
}

// ---- the failure policy --------------------------------------------------------------------

using CoordinatorPolicy = CoordinatorCoreTest;

TEST_F(CoordinatorPolicy, ContinueAnnouncesTheDeadAndKeepsTheSchedule) {
  config_.on_sensor_failure = FailurePolicy::Continue;
  const std::vector<EpisodeControl> first = starts(startRunning());
  now_ = first[0].start_wall_ns + 1250 * kMs;  // 1.25 s into episode 0
  const CoordinatorActions a = command(CommandKind::SensorsFailed, 11, {2});
  const std::vector<EpisodeControl> notice = controls(a, ControlKind::SensorsFailed);
  ASSERT_EQ(notice.size(), 1u);
  EXPECT_EQ(notice[0].episode, 0u);
  EXPECT_DOUBLE_EQ(notice[0].failed_at_s, 1.25);
  EXPECT_EQ(notice[0].failed_sensors, std::vector<std::uint32_t>{2});
  EXPECT_TRUE(only<PublishVersion>(a).empty());
  const std::vector<SendReply> reply = only<SendReply>(a);
  ASSERT_EQ(reply.size(), 1u);
  EXPECT_TRUE(reply[0].answer.accepted);
  EXPECT_EQ(reply[0].answer.reason, "policy continue: schedule unchanged");
  // The journal knows of the failure before anyone hears of it.
  const auto journal = std::find_if(a.begin(), a.end(), [](const CoordinatorAction& x) {
    return std::holds_alternative<WriteJournal>(x);
  });
  const auto published = std::find_if(a.begin(), a.end(), [](const CoordinatorAction& x) {
    return std::holds_alternative<PublishControl>(x);
  });
  ASSERT_NE(journal, a.end());
  EXPECT_LT(journal - a.begin(), published - a.begin());
  EXPECT_EQ(std::get<WriteJournal>(*journal).journal.settings.failed, std::set<int>{2});
  // The next episode announced counts it dead from its start.
  (void)report(0);
  const std::vector<EpisodeControl> next = starts(tickAt(now_));
  ASSERT_EQ(next.size(), 1u);
  EXPECT_EQ(next[0].failed_sensors, std::vector<std::uint32_t>{2});
  EXPECT_FALSE(core_->exitCode());
}

TEST_F(CoordinatorPolicy, StopEndsTheRunAsFailedAndTheCoordinatorExitsZero) {
  config_.on_sensor_failure = FailurePolicy::Stop;
  const std::vector<EpisodeControl> first = starts(startRunning());
  now_ = first[0].start_wall_ns + kSecond;
  const std::vector<SendReply> reply = only<SendReply>(command(CommandKind::SensorsFailed, 12, {1}));
  ASSERT_EQ(reply.size(), 1u);
  EXPECT_EQ(reply[0].answer.reason.rfind("policy stop: the run ends", 0), 0u)
      << reply[0].answer.reason;
  const CoordinatorActions end = tickAt(now_ + kMs);
  const std::vector<ShutDownRun> shutdown = only<ShutDownRun>(end);
  ASSERT_EQ(shutdown.size(), 1u);
  EXPECT_TRUE(shutdown[0].control.aborted);
  EXPECT_EQ(shutdown[0].control.detail, "sensor(s) 1 failed; --on-sensor-failure stop");
  const std::vector<ExitProgram> exit = only<ExitProgram>(end);
  ASSERT_EQ(exit.size(), 1u);
  EXPECT_EQ(exit[0].exit_code, 0) << "it stopped because it was told to";
  EXPECT_FALSE(exit[0].summary);
}

// Issue 31: the journal cannot be written (the log folder's disk is full) in the middle of the
// run. The run ends at the next tick, aborted with the reason, which every process and so the
// report get in the RUN_SHUTDOWN; nothing more is written to the journal.
TEST_F(CoordinatorCoreTest, AJournalThatCannotBeWrittenEndsTheRunWithTheReason) {
  const std::vector<EpisodeControl> first = starts(startRunning());
  ASSERT_FALSE(first.empty());  // two outstanding: episodes 0 and 1
  now_ = first[0].start_wall_ns + kSecond;
  core_->onJournalFailed("cannot write the coordinator journal logs/state.json: No space left on device");
  const CoordinatorActions end = tickAt(now_ + kMs);
  const std::vector<ShutDownRun> shutdown = only<ShutDownRun>(end);
  ASSERT_EQ(shutdown.size(), 1u);
  EXPECT_TRUE(shutdown[0].control.aborted);
  EXPECT_NE(shutdown[0].control.detail.find("logs/state.json: No space left on device"),
            std::string::npos)
      << shutdown[0].control.detail;
  EXPECT_NE(shutdown[0].control.detail.find("journal"), std::string::npos);
  EXPECT_TRUE(only<WriteJournal>(end).empty()) << "a journal that failed is not tried again";
  EXPECT_TRUE(starts(end).empty());
  ASSERT_EQ(only<ExitProgram>(end).size(), 1u);
  EXPECT_EQ(only<ExitProgram>(end)[0].exit_code, 0) << "it ended the run and said why";
  EXPECT_EQ(core_->exitCode(), 0);
}

// The first journal cannot be written (the log folder full from the start): the run ends once
// the fusion center, which writes the report, has joined, not before, so that it hears why.
TEST_F(CoordinatorCoreTest, AJournalFailedAtTheStartEndsTheRunOnceTheFusionCenterJoined) {
  (void)make();
  core_->onJournalFailed("cannot write the coordinator journal logs/state.json: No space left on device");
  EXPECT_TRUE(only<ShutDownRun>(tickAt(now_ + kMs)).empty()) << "nobody would hear of it";
  core_->onFusionCenterMatched(true);
  const CoordinatorActions end = tickAt(now_ + kMs);
  const std::vector<ShutDownRun> shutdown = only<ShutDownRun>(end);
  ASSERT_EQ(shutdown.size(), 1u);
  EXPECT_TRUE(shutdown[0].control.aborted);
  EXPECT_NE(shutdown[0].control.detail.find("No space left on device"), std::string::npos);
  EXPECT_EQ(shutdown[0].control.episodes_planned, 0u) << "no episode ran";
  EXPECT_EQ(core_->exitCode(), 0);
}

TEST_F(CoordinatorPolicy, ReplanGivesTheDeadRateZeroFromASwitchInTheRunningEpisode) {
  const std::vector<EpisodeControl> first = starts(startRunning());
  now_ = first[0].start_wall_ns + kSecond;
  fused(0, 0.9);
  const CoordinatorActions a = command(CommandKind::SensorsFailed, 13, {3});
  const std::vector<PublishVersion> versions = only<PublishVersion>(a);
  ASSERT_EQ(versions.size(), 2u) << "a mid-episode version and a full-horizon one";
  EXPECT_EQ(versions[0].version.version, 2u);
  EXPECT_EQ(versions[0].version.effective_episode, 0u);
  EXPECT_GT(versions[0].version.effective_time_s, 1.0);
  EXPECT_EQ(versions[1].version.version, 3u);
  EXPECT_EQ(versions[1].version.effective_episode, 1u);
  EXPECT_EQ(versions[1].version.effective_time_s, 0.0);
  for (const PublishVersion& v : versions) {
    EXPECT_EQ(v.version.schedule.rates().col(3).cwiseAbs().maxCoeff(), 0.0)
        << "version " << v.version.version;
  }
  const std::vector<SendReply> reply = only<SendReply>(a);
  ASSERT_EQ(reply.size(), 1u);
  EXPECT_EQ(reply[0].answer.schedule_version, 2u);
  EXPECT_EQ(reply[0].answer.reason.rfind("policy replan: ", 0), 0u) << reply[0].answer.reason;
}

TEST_F(CoordinatorPolicy, EverySensorDeadEndsTheRunUnderAnyPolicy) {
  config_.on_sensor_failure = FailurePolicy::Continue;
  (void)startRunning();
  (void)command(CommandKind::SensorsFailed, 14, {0, 1});
  EXPECT_FALSE(core_->exitCode());
  (void)tickAt(now_ + kMs);
  EXPECT_FALSE(core_->exitCode()) << "two of four left";
  const std::vector<SendReply> reply = only<SendReply>(command(CommandKind::SensorsFailed, 15, {2, 3}));
  ASSERT_EQ(reply.size(), 1u);
  EXPECT_EQ(reply[0].answer.reason.rfind("no policy applies", 0), 0u) << reply[0].answer.reason;
  const std::vector<ShutDownRun> shutdown = only<ShutDownRun>(tickAt(now_ + kMs));
  ASSERT_EQ(shutdown.size(), 1u);
  EXPECT_TRUE(shutdown[0].control.aborted);
  EXPECT_EQ(core_->exitCode(), 0);
}

TEST_F(CoordinatorPolicy, ASensorReportedDeadTwiceIsNothingNew) {
  config_.on_sensor_failure = FailurePolicy::Continue;
  (void)startRunning();
  (void)command(CommandKind::SensorsFailed, 16, {1});
  const CoordinatorActions again = command(CommandKind::SensorsFailed, 17, {1});
  EXPECT_TRUE(controls(again, ControlKind::SensorsFailed).empty());
  ASSERT_EQ(only<SendReply>(again).size(), 1u);
  EXPECT_EQ(only<SendReply>(again)[0].answer.reason,
            "sensor(s) 1 had failed before: nothing new");
}

// ---- deaths seen in liveliness (--sensor-deaths liveliness: no launcher, e.g. containers) -------

using CoordinatorLiveliness = CoordinatorCoreTest;

TEST_F(CoordinatorLiveliness, ASensorSilentForTheGraceIsDeadAndReplannedAround) {
  config_.sensor_deaths = DeathWitness::Liveliness;
  config_.death_grace_s = 2.0;
  const std::vector<EpisodeControl> first = starts(startRunning());
  now_ = first[0].start_wall_ns + 500 * kMs;
  fused(0, 0.4);
  core_->onSensorLiveliness(3, false, now_);
  const std::int64_t lost = now_;
  EXPECT_TRUE(controls(tickAt(lost + 1999 * kMs), ControlKind::SensorsFailed).empty())
      << "within the grace it may still be a stall";
  const CoordinatorActions a = tickAt(lost + 2000 * kMs);
  const std::vector<EpisodeControl> notice = controls(a, ControlKind::SensorsFailed);
  ASSERT_EQ(notice.size(), 1u);
  EXPECT_EQ(notice[0].failed_sensors, std::vector<std::uint32_t>{3});
  EXPECT_NE(notice[0].detail.find("liveliness"), std::string::npos) << notice[0].detail;
  // The default policy re-plans: rate zero for sensor 3 in every version published.
  const std::vector<PublishVersion> versions = only<PublishVersion>(a);
  ASSERT_FALSE(versions.empty());
  for (const PublishVersion& v : versions) {
    EXPECT_EQ(v.version.schedule.rates().col(3).cwiseAbs().maxCoeff(), 0.0)
        << "version " << v.version.version;
  }
  EXPECT_TRUE(only<SendReply>(a).empty()) << "nobody asked: nothing to answer";
  // Journal before publication, as for a launcher's notice.
  const auto journal = std::find_if(a.begin(), a.end(), [](const CoordinatorAction& x) {
    return std::holds_alternative<WriteJournal>(x);
  });
  ASSERT_NE(journal, a.end());
  EXPECT_EQ(std::get<WriteJournal>(*journal).journal.settings.failed, std::set<int>{3});
  EXPECT_TRUE(controls(tickAt(lost + 5 * kSecond), ControlKind::SensorsFailed).empty())
      << "declared once";
}

TEST_F(CoordinatorLiveliness, LivelinessBackWithinTheGraceIsAStallNotADeath) {
  config_.sensor_deaths = DeathWitness::Liveliness;
  const std::vector<EpisodeControl> first = starts(startRunning());
  now_ = first[0].start_wall_ns + 500 * kMs;
  core_->onSensorLiveliness(1, false, now_);
  core_->onSensorLiveliness(1, true, now_ + 1500 * kMs);
  EXPECT_TRUE(controls(tickAt(now_ + 10 * kSecond), ControlKind::SensorsFailed).empty());
}

TEST_F(CoordinatorLiveliness, TwoSensorsLostTogetherAreOneNoticeAndStopEndsTheRun) {
  config_.sensor_deaths = DeathWitness::Liveliness;
  config_.on_sensor_failure = FailurePolicy::Stop;
  const std::vector<EpisodeControl> first = starts(startRunning());
  now_ = first[0].start_wall_ns + 500 * kMs;
  core_->onSensorLiveliness(0, false, now_);
  core_->onSensorLiveliness(2, false, now_ + 100 * kMs);
  const CoordinatorActions a = tickAt(now_ + 2100 * kMs);
  const std::vector<EpisodeControl> notice = controls(a, ControlKind::SensorsFailed);
  ASSERT_EQ(notice.size(), 1u);
  EXPECT_EQ(notice[0].failed_sensors, (std::vector<std::uint32_t>{0, 2}));
  const std::vector<ShutDownRun> shutdown = only<ShutDownRun>(tickAt(now_ + 2200 * kMs));
  ASSERT_EQ(shutdown.size(), 1u);
  EXPECT_TRUE(shutdown[0].control.aborted);
  EXPECT_EQ(core_->exitCode(), 0);
}

TEST_F(CoordinatorLiveliness, BeforeTheFirstEpisodeAndUnderTheLauncherWitnessNothingDies) {
  config_.sensor_deaths = DeathWitness::Liveliness;
  (void)make();
  everySensorReady();
  core_->onSensorLiveliness(1, false, now_);  // lost while the run waits for its peers
  (void)tickAt(now_);
  const CoordinatorActions a = tickAt(now_ + config_.settle.count());
  EXPECT_TRUE(controls(a, ControlKind::SensorsFailed).empty());
  core_->onSensorLiveliness(1, true, now_);  // back before the grace ran out: no death
  EXPECT_TRUE(controls(tickAt(now_ + 5 * kSecond), ControlKind::SensorsFailed).empty());

  config_.sensor_deaths = DeathWitness::Launcher;  // the default: only notices count
  const std::vector<EpisodeControl> first = starts(startRunning());
  core_->onSensorLiveliness(1, false, first[0].start_wall_ns);
  EXPECT_TRUE(
      controls(tickAt(first[0].start_wall_ns + 5 * kSecond), ControlKind::SensorsFailed).empty());
}

TEST(DeathWitnessWords, ReadBackAndListTheChoices) {
  EXPECT_EQ(wordChoices<DeathWitness>(), "launcher or liveliness");
  EXPECT_EQ(lookUpWord<DeathWitness>("liveliness"), DeathWitness::Liveliness);
  EXPECT_EQ(lookUpWord<DeathWitness>("heartbeat"), std::nullopt);
}

// `sensornet replan --include` (issue 24): an excluded sensor comes back into the plan; a dead
// one cannot, and the reply says why.
TEST_F(CoordinatorPolicy, IncludeBringsAnExcludedSensorBackButNotADeadOne) {
  config_.on_sensor_failure = FailurePolicy::Continue;
  const auto excludedIn = [](const CoordinatorActions& a) {
    const std::vector<WriteJournal> journals = only<WriteJournal>(a);
    return journals.empty() ? std::set<int>{-1} : journals.back().journal.settings.excluded;
  };
  // The sensor version 1 measures most (the information plan leaves some idle), and another.
  const Eigen::MatrixXd v1 = freshJournal().versions[0].schedule.rates();
  Eigen::Index busiest = 0;
  (void)v1.colwise().sum().maxCoeff(&busiest);
  const auto back_in = static_cast<std::uint32_t>(busiest);
  const std::uint32_t other = back_in == 2 ? 1 : 2;
  (void)startRunning();
  ASSERT_EQ(excludedIn(command(CommandKind::ExcludeSensors, 18, {back_in, other})),
            (std::set<int>{static_cast<int>(back_in), static_cast<int>(other)}));
  const CoordinatorActions back = command(CommandKind::IncludeSensors, 19, {back_in});
  const std::vector<PublishVersion> versions = only<PublishVersion>(back);
  ASSERT_FALSE(versions.empty());
  EXPECT_GT(versions.back().version.schedule.rates().col(back_in).norm(), 0.0) << "back in";
  EXPECT_EQ(versions.back().version.schedule.rates().col(other).norm(), 0.0) << "stays excluded";
  ASSERT_EQ(only<SendReply>(back).size(), 1u);
  EXPECT_TRUE(only<SendReply>(back)[0].answer.accepted) << only<SendReply>(back)[0].answer.reason;
  EXPECT_EQ(excludedIn(back), std::set<int>{static_cast<int>(other)});

  (void)command(CommandKind::SensorsFailed, 20, {other});
  const CoordinatorActions dead = command(CommandKind::IncludeSensors, 21, {other});
  EXPECT_TRUE(only<PublishVersion>(dead).empty());
  const std::vector<SendReply> refused = only<SendReply>(dead);
  ASSERT_EQ(refused.size(), 1u);
  EXPECT_FALSE(refused[0].answer.accepted);
  EXPECT_NE(refused[0].answer.reason.find("sensor " + std::to_string(other) +
                                           " failed (its process died)"),
            std::string::npos)
      << refused[0].answer.reason;
}

// ---- the switch moment ---------------------------------------------------------------------

using CoordinatorSwitchMoment = CoordinatorCoreTest;

TEST_F(CoordinatorSwitchMoment, MidEpisodeTheSwitchIsAMarginAheadOnATick) {
  const std::vector<EpisodeControl> first = starts(startRunning());
  now_ = first[0].start_wall_ns + kSecond;
  fused(0, 0.9);
  const std::vector<PublishVersion> v = only<PublishVersion>(command(CommandKind::Replan, 21));
  ASSERT_EQ(v.size(), 2u);
  const EmulatedPlant plant(run_.scenario, run_.seed);
  const double tick = plant.timeOf(1) - plant.timeOf(0);
  EXPECT_EQ(v[0].version.effective_episode, 0u);
  EXPECT_NEAR(v[0].version.effective_time_s, 1.0 + config_.switch_margin_s, tick);
  EXPECT_GE(v[0].version.effective_time_s, 1.0 + 0.5 * config_.switch_margin_s);
  EXPECT_EQ(v[1].version.effective_episode, 1u);
}

TEST_F(CoordinatorSwitchMoment, AnEpisodeAboutToStartKeepsItsVersion) {
  const std::vector<EpisodeControl> first = starts(startRunning());
  now_ = first[1].start_wall_ns - 100 * kMs;  // episode 1 starts within the 0.3 s margin
  fused(0, 2.8);
  const std::vector<PublishVersion> v = only<PublishVersion>(command(CommandKind::Replan, 22));
  ASSERT_EQ(v.size(), 1u) << "no episode runs long enough for a switch";
  EXPECT_EQ(v[0].version.effective_episode, 2u);
  EXPECT_EQ(v[0].version.effective_time_s, 0.0);
}

TEST_F(CoordinatorSwitchMoment, BetweenEpisodesTheNextOneTakesTheNewVersion) {
  config_.episode_gap_s = 1.0;
  const std::vector<EpisodeControl> first = starts(startRunning());
  now_ = first[1].start_wall_ns - 500 * kMs;  // episode 0 is over, 1 starts in 0.5 s
  const std::vector<PublishVersion> v = only<PublishVersion>(command(CommandKind::Replan, 23));
  ASSERT_EQ(v.size(), 1u);
  EXPECT_EQ(v[0].version.effective_episode, 1u);
}

TEST_F(CoordinatorSwitchMoment, RunningWithoutAFusedCovarianceOfItSwitchesAtTheNextEpisode) {
  const std::vector<EpisodeControl> first = starts(startRunning());
  now_ = first[0].start_wall_ns + kSecond;
  const std::vector<PublishVersion> v = only<PublishVersion>(command(CommandKind::Replan, 24));
  ASSERT_EQ(v.size(), 1u);
  EXPECT_EQ(v[0].version.effective_episode, 1u);
}

// ---- commands ------------------------------------------------------------------------------

using CoordinatorCommands = CoordinatorCoreTest;

TEST_F(CoordinatorCommands, ARepeatedCommandIsAnsweredOnceAndItsReplySentAgain) {
  const std::vector<EpisodeControl> first = starts(startRunning());
  now_ = first[0].start_wall_ns + kSecond;
  const CoordinatorActions once = command(CommandKind::Replan, 31);
  ASSERT_EQ(only<PublishVersion>(once).size(), 1u);
  ASSERT_EQ(only<SendReply>(once).size(), 1u);
  const CoordinatorActions twice = command(CommandKind::Replan, 31);
  EXPECT_TRUE(only<PublishVersion>(twice).empty());
  EXPECT_TRUE(only<WriteJournal>(twice).empty());
  const std::vector<SendReply> reply = only<SendReply>(twice);
  ASSERT_EQ(reply.size(), 1u);
  EXPECT_EQ(reply[0].answer, only<SendReply>(once)[0].answer);
  EXPECT_EQ(reply[0].command_id, 31u);
}

TEST_F(CoordinatorCommands, ARefusalIsRememberedAndSentAgainToo) {
  (void)startRunning();
  CommandEvent c;
  c.run_id = config_.run_id;
  c.command_id = 32;
  c.kind = CommandKind::Replan;
  c.surrogate = "newton";
  const std::vector<SendReply> first = only<SendReply>(core_->onCommand(c, now_));
  ASSERT_EQ(first.size(), 1u);
  EXPECT_FALSE(first[0].answer.accepted);
  c.surrogate = "cov";  // the same id: answered already, whatever it says now
  const std::vector<SendReply> again = only<SendReply>(core_->onCommand(c, now_));
  ASSERT_EQ(again.size(), 1u);
  EXPECT_EQ(again[0].answer, first[0].answer);
}

TEST_F(CoordinatorCommands, AnUnknownKindIsRefusedAndAnotherRunsCommandIgnored) {
  (void)startRunning();
  EXPECT_FALSE(only<SendReply>(command(CommandKind::Unknown, 33))[0].answer.accepted);
  CommandEvent other;
  other.run_id = "run-b";
  other.command_id = 34;
  other.kind = CommandKind::Status;
  EXPECT_TRUE(core_->onCommand(other, now_).empty());
}

TEST_F(CoordinatorCommands, ShutdownEndsTheRunAfterTheEpisodesAnnounced) {
  (void)startRunning();
  (void)command(CommandKind::Shutdown, 35);
  (void)report(0);
  EXPECT_TRUE(starts(tickAt(now_ + kMs)).empty());
  EXPECT_FALSE(core_->exitCode()) << "episode 1 was announced: it runs";
  (void)report(1);
  const std::vector<ShutDownRun> shutdown = only<ShutDownRun>(tickAt(now_ + kMs));
  ASSERT_EQ(shutdown.size(), 1u);
  EXPECT_FALSE(shutdown[0].control.aborted);
  EXPECT_EQ(shutdown[0].control.episodes_planned, 2u);
  EXPECT_EQ(core_->exitCode(), 0);
}

// ---- deadlines, signals --------------------------------------------------------------------

using CoordinatorDeadlines = CoordinatorCoreTest;

TEST_F(CoordinatorDeadlines, NoSignOfTheFusionCenterAfterAnEpisodeEndsExitsOne) {
  const std::vector<EpisodeControl> first = starts(startRunning());
  const std::int64_t end0 = first[0].start_wall_ns + horizon_ns_;
  for (std::int64_t t = end0; t < end0 + 30 * kSecond; t += 400 * kMs) {  // ticks, no stall
    (void)tickAt(t);
    EXPECT_FALSE(core_->exitCode()) << "silent for " << 1e-9 * static_cast<double>(t - end0);
  }
  (void)tickAt(end0 + 29'900 * kMs);
  EXPECT_FALSE(core_->exitCode()) << "29.9 s of silence is within the 30 s limit";
  const CoordinatorActions late = tickAt(end0 + 30'100 * kMs);
  const std::vector<ShutDownRun> shutdown = only<ShutDownRun>(late);
  ASSERT_EQ(shutdown.size(), 1u);
  EXPECT_EQ(shutdown[0].control.detail, "no report of episode 0");
  EXPECT_EQ(core_->exitCode(), kCoordinatorExitFailed);
}

TEST_F(CoordinatorDeadlines, FusionStatesKeepTheRunWaiting) {
  const std::vector<EpisodeControl> first = starts(startRunning());
  const std::int64_t end0 = first[0].start_wall_ns + horizon_ns_;
  for (std::int64_t t = end0; t <= end0 + 60 * kSecond; t += 400 * kMs) {
    (void)tickAt(t);
    fused(0, 3.0);
  }
  EXPECT_FALSE(core_->exitCode());
}

TEST_F(CoordinatorDeadlines, ItsOwnStallDoesNotCountAsTheFusionCentersSilence) {
  const std::vector<EpisodeControl> first = starts(startRunning());
  const std::int64_t end0 = first[0].start_wall_ns + horizon_ns_;
  (void)tickAt(end0);
  (void)tickAt(end0 + 40 * kSecond);  // this process did not run for 40 s
  EXPECT_FALSE(core_->exitCode());
}

TEST_F(CoordinatorDeadlines, ASignalEndsTheRunAsAbortedWithExitZero) {
  (void)startRunning();
  core_->onStopSignal();
  const std::vector<ShutDownRun> shutdown = only<ShutDownRun>(tickAt(now_ + kMs));
  ASSERT_EQ(shutdown.size(), 1u);
  EXPECT_TRUE(shutdown[0].control.aborted);
  EXPECT_EQ(shutdown[0].control.detail, "the coordinator was stopped by a signal");
  EXPECT_EQ(core_->exitCode(), 0);
}

TEST_F(CoordinatorDeadlines, AMalformedFusionStateIsCountedAndChangesNothing) {
  (void)startRunning();
  EXPECT_TRUE(only<WriteJournal>(core_->onFusionState({0, 1.0, 2, {1.0}}, now_)).empty());
  EXPECT_EQ(core_->rejectedSamples(), 1u);
}

// ---- the journal and a resume --------------------------------------------------------------

using CoordinatorResume = CoordinatorCoreTest;

TEST_F(CoordinatorResume, KilledBetweenTheJournalWriteAndTheAnnouncementItAnnouncesAgain) {
  const CoordinatorActions first = startRunning();
  // The journal written just before episode 1's announcement: the coordinator dies there.
  std::optional<CoordinatorJournal> before_announcement;
  std::int64_t start1 = 0;
  for (const CoordinatorAction& a : first) {
    if (const auto* w = std::get_if<WriteJournal>(&a)) before_announcement = w->journal;
    const auto* p = std::get_if<PublishControl>(&a);
    if (p && p->control.episode == 1) {
      start1 = p->control.start_wall_ns;
      break;
    }
  }
  ASSERT_TRUE(before_announcement);
  ASSERT_TRUE(before_announcement->announced);
  EXPECT_EQ(before_announcement->announced->episode, 1u) << "written before it went out";
  EXPECT_EQ(before_announcement->announced->start_wall_ns, start1);

  now_ += 2 * kSecond;  // restarted
  (void)make(*before_announcement);
  everySensorReady();
  (void)tickAt(now_);
  const std::vector<EpisodeControl> again = starts(tickAt(now_ + config_.settle.count()));
  ASSERT_EQ(again.size(), 1u) << "episode 0's report is still owed: two outstanding";
  EXPECT_EQ(again[0].episode, 1u) << "the announcement the others may have missed";
  EXPECT_EQ(again[0].start_wall_ns, start1) << "as it was";
  (void)report(0);
  const std::vector<EpisodeControl> after0 = starts(tickAt(now_ + kMs));
  ASSERT_EQ(after0.size(), 1u);
  EXPECT_EQ(after0[0].episode, 2u);
  EXPECT_EQ(after0[0].start_wall_ns, start1 + horizon_ns_ + 2 * kMs);
  (void)report(1);
  const std::vector<EpisodeControl> next = starts(tickAt(now_ + 2 * kMs));
  ASSERT_EQ(next.size(), 1u);
  EXPECT_EQ(next[0].episode, 3u);
}

// Chaos seed 435: killed while episodes 3 and 4 were outstanding, with 4 announced last; the
// fusion center closed 4 before 3. The resumed coordinator waits for both reports before it
// ends the run, in whichever order they come (it ended it after 4's, with 3 still open).
TEST_F(CoordinatorResume, AwaitsEveryAnnouncedEpisodeStillOwedItsReport) {
  config_.episodes = 5;
  CoordinatorJournal journal = freshJournal();
  for (std::uint32_t e = 0; e < 3; ++e) journal.episodes_reported.insert(e);
  journal.announced = AnnouncedEpisode{4, now_ - kSecond};
  (void)make(journal);
  everySensorReady();
  (void)tickAt(now_);
  const std::vector<EpisodeControl> again = starts(tickAt(now_ + config_.settle.count()));
  ASSERT_EQ(again.size(), 1u);
  EXPECT_EQ(again[0].episode, 4u);
  (void)report(4);
  EXPECT_TRUE(only<ShutDownRun>(tickAt(now_ + kMs)).empty()) << "episode 3 is still open";
  EXPECT_FALSE(core_->exitCode());
  (void)report(3);
  const std::vector<ShutDownRun> shutdown = only<ShutDownRun>(tickAt(now_ + kMs));
  ASSERT_EQ(shutdown.size(), 1u);
  EXPECT_EQ(shutdown[0].control.episodes_planned, 5u) << "RUN_SHUTDOWN says how many ran";
}

// ... at its first tick with the fusion center there (which writes the report), not before.
TEST_F(CoordinatorResume, AJournalThatSaysTheRunWasAbortedEndsItOnceTheFusionCenterHearsIt) {
  CoordinatorJournal journal = freshJournal();
  journal.abort_detail = "sensor(s) 1 failed; --on-sensor-failure stop";
  EXPECT_TRUE(only<ShutDownRun>(make(journal)).empty());
  EXPECT_TRUE(only<ShutDownRun>(tickAt(now_ + kMs)).empty());
  core_->onFusionCenterMatched(true);
  const CoordinatorActions a = tickAt(now_ + kMs);
  const std::vector<ShutDownRun> shutdown = only<ShutDownRun>(a);
  ASSERT_EQ(shutdown.size(), 1u);
  EXPECT_EQ(shutdown[0].control.detail, journal.abort_detail);
  EXPECT_EQ(core_->exitCode(), 0);
}

TEST_F(CoordinatorResume, StartPublishesTheJournalTheScenarioAndEveryVersionInThatOrder) {
  const CoordinatorActions a = make();
  ASSERT_GE(a.size(), 3u);
  EXPECT_TRUE(std::holds_alternative<WriteJournal>(a[0]));
  EXPECT_TRUE(std::holds_alternative<PublishScenario>(a[1]));
  ASSERT_TRUE(std::holds_alternative<PublishVersion>(a[2]));
  EXPECT_EQ(std::get<PublishVersion>(a[2]).version.version, 1u);
}

TEST(FailurePolicyWords, ReadBackAndListTheChoices) {
  EXPECT_EQ(wordChoices<FailurePolicy>(), "replan, continue or stop");
  EXPECT_EQ(lookUpWord<FailurePolicy>("stop"), FailurePolicy::Stop);
  EXPECT_EQ(wordOf(SensorState::Excluded), "excluded");
}

// Commands by right (issue 30): a failure notice from an operator, or a re-plan from the
// launcher, is refused whatever its issuer field says: the reply begins "not permitted: ",
// nothing is announced or re-planned, and the same command coming again gets the same answer.
TEST_F(CoordinatorCommands, ACommandFromASenderWithoutTheRightIsRefused) {
  config_.on_sensor_failure = FailurePolicy::Continue;
  (void)startRunning();
  const std::vector<SendReply> forged =
      only<SendReply>(command(CommandKind::SensorsFailed, 21, {2}, CommandSender::Operator));
  ASSERT_EQ(forged.size(), 1u);
  EXPECT_FALSE(forged[0].answer.accepted);
  EXPECT_EQ(forged[0].answer.reason.rfind(std::string(kNotPermitted), 0), 0u)
      << forged[0].answer.reason;
  EXPECT_NE(forged[0].answer.reason.find("only the launcher may report sensors failed"),
            std::string::npos);
  const CoordinatorActions again =
      command(CommandKind::SensorsFailed, 21, {2}, CommandSender::Operator);
  EXPECT_TRUE(controls(again, ControlKind::SensorsFailed).empty()) << "announced a forged death";
  const std::vector<SendReply> replan =
      only<SendReply>(command(CommandKind::Replan, 22, {}, CommandSender::Launcher));
  ASSERT_EQ(replan.size(), 1u);
  EXPECT_FALSE(replan[0].answer.accepted);
  EXPECT_EQ(replan[0].answer.schedule_version, 0u);
  // The rightful sender's notice is obeyed.
  const CoordinatorActions real = command(CommandKind::SensorsFailed, 23, {2});
  EXPECT_EQ(controls(real, ControlKind::SensorsFailed).size(), 1u);
}

// ---- closed loop (--replan-every) ----------------------------------------------------------

class CoordinatorClosedLoop : public CoordinatorCoreTest {
 protected:
  CoordinatorClosedLoop() { config_.replan_every_s = 1.0; }  // T = 3: instants 1 s and 2 s

  static std::vector<PublishVersion> versions(const CoordinatorActions& actions) {
    return only<PublishVersion>(actions);
  }
};

TEST_F(CoordinatorClosedLoop, EachInstantReplansTheTailAndTheOpenLoopPlanComesBackNextEpisode) {
  const std::vector<EpisodeControl> first = starts(startRunning());
  const RateSchedule open_loop = freshJournal().versions.front().schedule;
  const EmulatedPlant plant(run_.scenario, run_.seed);
  const double tick = plant.timeOf(1) - plant.timeOf(0);

  now_ = first[0].start_wall_ns + 500 * kMs;
  fused(0, 0.45);
  EXPECT_TRUE(versions(tickAt(now_)).empty()) << "before the first instant";

  now_ = first[0].start_wall_ns + kSecond + 5 * kMs;
  fused(0, 0.98);
  const CoordinatorActions at_one = tickAt(now_);
  const std::vector<PublishVersion> v = versions(at_one);
  ASSERT_EQ(v.size(), 2u);
  EXPECT_EQ(v[0].version.version, 2u);
  EXPECT_EQ(v[0].version.effective_episode, 0u);
  EXPECT_NEAR(v[0].version.effective_time_s, 1.005 + config_.switch_margin_s, tick);
  EXPECT_EQ(v[0].version.surrogate, SurrogateKind::Information);
  EXPECT_EQ(v[1].version.version, 3u);
  EXPECT_EQ(v[1].version.effective_episode, 1u);
  EXPECT_EQ(v[1].version.effective_time_s, 0.0);
  EXPECT_EQ(v[1].version.schedule.rates(), open_loop.rates()) << "the open-loop plan, bit for bit";
  // The journal records the versions before they go out.
  const auto journal_at = std::find_if(at_one.begin(), at_one.end(), [](const auto& a) {
    return std::holds_alternative<WriteJournal>(a);
  });
  const auto first_version = std::find_if(at_one.begin(), at_one.end(), [](const auto& a) {
    return std::holds_alternative<PublishVersion>(a);
  });
  EXPECT_LT(journal_at - at_one.begin(), first_version - at_one.begin());

  now_ += 20 * kMs;
  EXPECT_TRUE(versions(tickAt(now_)).empty()) << "the instant is served once";

  now_ = first[0].start_wall_ns + 2 * kSecond + 5 * kMs;  // the same fused covariance still
  const std::vector<PublishVersion> w = versions(tickAt(now_));
  ASSERT_EQ(w.size(), 2u);
  EXPECT_EQ(w[0].version.version, 4u);
  EXPECT_NEAR(w[0].version.effective_time_s, 2.005 + config_.switch_margin_s, tick);
  EXPECT_EQ(w[1].version.schedule.rates(), open_loop.rates())
      << "from the next episode the open-loop plan, not the last tail";
}

TEST_F(CoordinatorClosedLoop, WithoutAFusedCovarianceOfTheEpisodeItWaitsAndServesTheInstantLate) {
  const std::vector<EpisodeControl> first = starts(startRunning());
  now_ = first[0].start_wall_ns + kSecond + 5 * kMs;
  const CoordinatorActions waiting = tickAt(now_);
  EXPECT_TRUE(versions(waiting).empty());
  EXPECT_FALSE(only<LogLine>(waiting).empty()) << "it says why";
  now_ += 300 * kMs;
  EXPECT_TRUE(only<LogLine>(tickAt(now_)).empty()) << "said once";
  fused(0, 1.2);
  now_ += 10 * kMs;
  const CoordinatorActions served = tickAt(now_);
  const std::vector<PublishVersion> v = versions(served);
  std::string said;
  for (const LogLine& line : only<LogLine>(served)) said += line.text + "\n";
  ASSERT_EQ(v.size(), 2u) << said;
  EXPECT_NEAR(v[0].version.effective_time_s, 1.315 + config_.switch_margin_s, 1e-3);
}

TEST_F(CoordinatorClosedLoop, NoInstantWhoseSwitchWouldFallPastTheHorizonPublishes) {
  config_.replan_every_s = 2.8;  // T = 3, margin 0.3: 2.8 + 0.3 > T
  const std::vector<EpisodeControl> first = starts(startRunning());
  now_ = first[0].start_wall_ns + 2800 * kMs + 5 * kMs;
  fused(0, 2.7);
  EXPECT_TRUE(versions(tickAt(now_)).empty());
}

TEST_F(CoordinatorClosedLoop, OpenLoopPublishesNothingOnItsOwn) {
  config_.replan_every_s.reset();
  const std::vector<EpisodeControl> first = starts(startRunning());
  for (int i = 1; i <= 28; ++i) {
    now_ = first[0].start_wall_ns + i * 100 * kMs;
    fused(0, 0.1 * i - 0.05);
    EXPECT_TRUE(versions(tickAt(now_)).empty()) << "at " << 0.1 * i << " s";
  }
}

}  // namespace
}  // namespace sensornet::emulator
