// SensorAgentCore (sensor_agent_core.hpp): what a sensor agent decides, on a fake clock, fed the
// same wire samples a run's topics carry (through RunInputState, as the executable feeds it).
// Every expectation is recomputed here from the scenario, the schedule and the fake times:
// which measurement goes out at which tick, what each tally counts, which status each hosted
// sensor shows, how far behind the clock it says it fell.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "sensornet/core/input_error.hpp"
#include "sensornet/dds/wire.hpp"
#include "sensornet/wire/messages.hpp"
#include "sensornet/wire/run_inputs.hpp"
#include "sensornet/emulator/sensor_agent_core.hpp"
#include "sensornet/io/scenario_file.hpp"

namespace sensornet::emulator {
namespace {

using namespace sensornet::wire;  // the samples a run carries, fed to the core as live

constexpr std::int64_t kSecond = 1'000'000'000;
constexpr std::uint64_t kSeed = 17;
constexpr auto kIdle = std::chrono::milliseconds(100);

// n = 2 with a non-symmetric A, M = 3, T = 1 s in two intervals. The agent hosts sensors 0 and
// 2 (not 1), so that an index mixed up between hosted and scenario sensors shows.
const std::string kYaml =
    "horizon: 1.0\nintervals: 2\n"
    "plant:\n  A: [[0, 1], [-2, -0.5]]\n  Q: [[0.1, 0], [0, 0.2]]\n  P0: [[1, 0], [0, 2]]\n"
    "sensors:\n  - H: [[1, 0]]\n    R: [[0.5]]\n  - H: [[0, 1]]\n    R: [[0.3]]\n"
    "  - H: [[1, 1]]\n    R: [[0.2]]\n"
    "constraints:\n  C: [[1, 1, 1]]\n  b: [200]\n";

// Every measurement held back 0.3 s by the emulated network.
const std::string kDelayedYaml = kYaml + "network:\n  default: {delay: {fixed: 0.3}}\n";

template <class A>
std::vector<A> only(const SensorAgentActions& actions) {
  std::vector<A> out;
  for (const SensorAgentAction& a : actions) {
    if (const A* x = std::get_if<A>(&a)) out.push_back(*x);
  }
  return out;
}

template <class A>
bool contains(const SensorAgentActions& actions) {
  return !only<A>(actions).empty();
}

bool logs(const SensorAgentActions& actions, const std::string& fragment) {
  return std::any_of(actions.begin(), actions.end(), [&](const SensorAgentAction& a) {
    const LogLine* line = std::get_if<LogLine>(&a);
    return line != nullptr && line->text.find(fragment) != std::string::npos;
  });
}

// A measurement handed out, with the fake time of the tick that handed it out.
struct Sent {
  std::int64_t at_ns = 0;
  PublishMeasurement what;
};

class SensorAgentCoreTest : public ::testing::Test {
 protected:
  void SetUp() override { (void)core_.start(now_); }

  void announceScenario(const std::string& yaml = kYaml) {
    run_.yaml = yaml;
    run_.scenario = parseScenarioYaml(yaml, "test");
    run_.digest = digestOf(yaml);
    run_.seed = kSeed;
    withScenarioSample("run", run_, [&](const sensornet_Scenario& s) {
      feedSample(inputs_, s, update_);
    });
  }

  // Rates in Hz, one row per interval, one column per scenario sensor.
  void announceVersion(std::uint32_t number, std::uint32_t episode, double at,
                       const Eigen::MatrixXd& rates) {
    ScheduleVersion v;
    v.version = number;
    v.effective_episode = episode;
    v.effective_time_s = at;
    v.schedule = RateSchedule(run_.scenario.horizon_s, rates);
    v.surrogate = SurrogateKind::File;
    withScheduleSample("run", run_.digest, v, [&](const sensornet_Schedule& s) {
      feedSample(inputs_, s, update_);
    });
  }

  void control(sensornet_EpisodeCommand command, std::uint32_t episode, std::int64_t start_ns,
               std::uint32_t version = 1, std::vector<std::uint32_t> failed = {}) {
    const std::string empty;
    sensornet_EpisodeControl c{};
    c.run_id = dds::borrowString(empty);
    c.episode = episode;
    c.command = command;
    c.start_wall_time_ns = start_ns;
    c.time_scale = 1.0;
    c.seed = kSeed;
    c.schedule_version = version;
    c.episodes_planned = 5;
    c.detail = dds::borrowString(empty);
    dds::borrowSequence(c.failed_sensors, std::span<const std::uint32_t>(failed));
    feedSample(inputs_, c, update_);
  }

  // What RunInputState made of the samples since the last feed, handed to the core.
  SensorAgentActions feed() {
    inputs_.releaseStarts(update_);
    SensorAgentActions out = core_.onInputs(update_, now_);
    update_ = {};
    return out;
  }

  void discover() { core_.onDiscovery({true, true, true}); }

  // Ticks every `step` until `until_ns`, collecting what comes out.
  SensorAgentActions runUntil(std::int64_t until_ns, std::int64_t step_ns,
                              std::vector<Sent>* sent = nullptr) {
    SensorAgentActions all;
    while (now_ < until_ns && !core_.exitCode()) {
      now_ = std::min(until_ns, now_ + step_ns);
      for (SensorAgentAction& a : core_.tick(now_)) {
        if (sent != nullptr) {
          if (const auto* m = std::get_if<PublishMeasurement>(&a)) sent->push_back({now_, *m});
        }
        all.push_back(std::move(a));
      }
    }
    return all;
  }

  // Scenario `yaml`, version 1 with `rates`, everything matched, episode 0 (without the
  // `failed` sensors) starting 0.1 s from now; returns its start.
  std::int64_t startEpisodeZero(const std::string& yaml, const Eigen::MatrixXd& rates,
                                std::vector<std::uint32_t> failed = {}) {
    announceScenario(yaml);
    announceVersion(1, 0, 0.0, rates);
    discover();
    const std::int64_t start = now_ + kSecond / 10;
    control(sensornet_EPISODE_START, 0, start, 1, std::move(failed));
    (void)feed();
    return start;
  }
  // The usual start: sensor 0 at 30 Hz then 10 Hz, sensor 2 at 20 Hz.
  std::int64_t startEpisodeZero() {
    Eigen::MatrixXd rates(2, 3);
    rates << 30, 0, 20,  //
        10, 0, 20;
    return startEpisodeZero(kYaml, rates);
  }

  std::int64_t now_ = 1'000 * kSecond;
  RunScenario run_;
  RunInputState inputs_;
  RunInputState::Update update_;
  SensorAgentCore core_{{{0, 2}, 1.0}, inputs_};
};

TEST_F(SensorAgentCoreTest, EachMeasurementGoesOutAtTheFirstTickAtOrAfterItsInstant) {
  const std::int64_t start = startEpisodeZero();
  const std::int64_t step = kSecond / 1000;  // a 1 ms tick
  std::vector<Sent> sent;
  const SensorAgentActions actions = runUntil(start + 2 * kSecond, step, &sent);

  std::map<int, std::uint64_t> per_sensor;
  double last_time = -1.0;
  for (const Sent& s : sent) {
    const HeldMeasurement& m = s.what.measurement;
    ASSERT_TRUE(m.sensor == 0 || m.sensor == 2) << "sensor 1 is not hosted";
    EXPECT_EQ(s.what.episode, 0U);
    EXPECT_EQ(m.seq, per_sensor[m.sensor]++) << "seq 0, 1, ... per sensor";
    EXPECT_GE(m.time_s, last_time) << "in emulated-time order";
    last_time = m.time_s;
    const std::int64_t due = start + static_cast<std::int64_t>(1e9 * m.time_s);
    EXPECT_GE(s.at_ns, due) << "never before its instant";
    EXPECT_LT(s.at_ns - step, due) << "at the first tick at or after it";
    ASSERT_EQ(m.z.size(), 1);
    EXPECT_TRUE(std::isfinite(m.z(0)));
    EXPECT_EQ(m.version, 1U);
    EXPECT_LE(m.time_s, 1.0);
  }
  // Poisson counts: 20 Hz + 10 Hz over the two halves for sensor 0 (mean 20), 20 Hz for sensor
  // 2 (mean 20). The 99.9% two-sided quantiles of Poisson(20) are 7 and 36 (seeded: fixed).
  EXPECT_GE(per_sensor[0], 7U);
  EXPECT_LE(per_sensor[0], 36U);
  EXPECT_GE(per_sensor[2], 7U);
  EXPECT_LE(per_sensor[2], 36U);

  const auto tallies = only<PublishTally>(actions);
  ASSERT_EQ(tallies.size(), 2U);
  for (const PublishTally& t : tallies) {
    EXPECT_EQ(t.sent, per_sensor[t.sensor]);
    EXPECT_TRUE(t.finished);
    EXPECT_EQ(t.dropped_by_network, 0U);
    EXPECT_LE(t.max_lag_s, 1e-3 + 1e-9) << "a 1 ms tick is at most 1 ms late";
    EXPECT_GE(t.wall_time_ns, start + kSecond) << "not before T";
    EXPECT_LT(t.wall_time_ns, start + kSecond + step + 1) << "at the first tick at or after T";
  }
  // Status: running when the episode began, ready after it (no other was announced).
  const auto statuses = only<PublishSensorStatus>(actions);
  ASSERT_FALSE(statuses.empty());
  EXPECT_EQ(statuses.front().state, SensorState::Running);
  EXPECT_EQ(statuses.back().state, SensorState::Ready);
}

TEST_F(SensorAgentCoreTest, ReadyOnlyWithScenarioScheduleAndEveryEndpointMatched) {
  EXPECT_EQ(core_.state(), SensorState::Starting);
  announceScenario();
  (void)feed();
  EXPECT_EQ(core_.state(), SensorState::Starting) << "no schedule yet";
  Eigen::MatrixXd rates = Eigen::MatrixXd::Constant(2, 3, 5.0);
  announceVersion(1, 0, 0.0, rates);
  (void)feed();
  EXPECT_EQ(core_.state(), SensorState::Starting) << "nothing matched yet";
  core_.onDiscovery({true, true, false});
  EXPECT_EQ(core_.state(), SensorState::Starting) << "the tally writer has no reader";
  core_.onDiscovery({false, true, true});
  EXPECT_EQ(core_.state(), SensorState::Starting) << "the control reader has no writer";
  discover();
  EXPECT_EQ(core_.state(), SensorState::Ready);
  // The change goes out at the next tick, for both hosted sensors, with the version and rate.
  const auto statuses = only<PublishSensorStatus>(core_.tick(now_ + 1));
  ASSERT_EQ(statuses.size(), 2U);
  EXPECT_EQ(statuses[0].sensor, 0);
  EXPECT_EQ(statuses[1].sensor, 2);
  for (const auto& s : statuses) {
    EXPECT_EQ(s.state, SensorState::Ready);
    EXPECT_EQ(s.schedule_version, 1U);
    EXPECT_DOUBLE_EQ(s.current_rate_hz, 5.0);
  }
  // Unchanged: nothing until the status period (1 s) has passed.
  EXPECT_TRUE(only<PublishSensorStatus>(core_.tick(now_ + kSecond / 2)).empty());
  EXPECT_EQ(only<PublishSensorStatus>(core_.tick(now_ + kSecond + 2)).size(), 2U);
}

TEST_F(SensorAgentCoreTest, ASensorTheScheduleGivesNoRateShowsExcluded) {
  announceScenario();
  Eigen::MatrixXd rates(2, 3);
  rates << 5, 5, 0,  //
      5, 5, 0;
  announceVersion(1, 0, 0.0, rates);
  discover();
  const auto statuses = only<PublishSensorStatus>(feed());  // a new version: its status at once
  ASSERT_EQ(statuses.size(), 2U);
  EXPECT_EQ(statuses[0].state, SensorState::Ready);
  EXPECT_EQ(statuses[1].state, SensorState::Excluded) << "sensor 2 has rate 0 throughout";
}

TEST_F(SensorAgentCoreTest, ASwitchMidEpisodeChangesOnlyWhatIsNotYetPublished) {
  const std::int64_t start = startEpisodeZero();
  std::vector<Sent> sent;
  (void)runUntil(start + kSecond / 4, kSecond / 1000, &sent);
  const std::size_t before = sent.size();
  ASSERT_GT(before, 0U);
  // Version 2 from 0.5 s of episode 0: sensor 0 silent, sensor 2 at 40 Hz.
  Eigen::MatrixXd rates(2, 3);
  rates << 0, 0, 40,  //
      0, 0, 40;
  announceVersion(2, 0, 0.5, rates);
  EXPECT_FALSE(logs(feed(), "arrived after")) << "in time: no warning";
  (void)runUntil(start + 2 * kSecond, kSecond / 1000, &sent);
  for (std::size_t i = 0; i < sent.size(); ++i) {
    const HeldMeasurement& m = sent[i].what.measurement;
    if (m.time_s < 0.5) {
      EXPECT_EQ(m.version, 1U) << "before the switch";
    } else {
      EXPECT_EQ(m.version, 2U) << "from the switch on";
      EXPECT_EQ(m.sensor, 2) << "sensor 0 has rate 0 from 0.5 s";
    }
  }
  // A switch whose instant has passed is taken for the rest, with a warning.
  Eigen::MatrixXd later = Eigen::MatrixXd::Constant(2, 3, 10.0);
  control(sensornet_EPISODE_START, 1, now_ + kSecond / 10, 2);
  (void)feed();
  (void)runUntil(now_ + kSecond / 10 + 6 * kSecond / 10, kSecond / 1000);
  announceVersion(3, 1, 0.2, later);
  EXPECT_TRUE(logs(feed(), "schedule switch at 0.2 s arrived after"));
}

TEST_F(SensorAgentCoreTest, TheNextEpisodeAnnouncedEarlyStartsOnlyAfterThisOnesTally) {
  const std::int64_t start = startEpisodeZero();
  (void)runUntil(start + kSecond / 2, kSecond / 1000);
  control(sensornet_EPISODE_START, 1, start + kSecond + kSecond / 100);
  (void)feed();
  std::vector<Sent> sent;
  const SensorAgentActions actions = runUntil(start + 3 * kSecond, kSecond / 1000, &sent);
  // Every tally of episode 0 comes before the first measurement of episode 1.
  std::size_t last_tally0 = 0;
  std::size_t first_m1 = actions.size();
  for (std::size_t i = 0; i < actions.size(); ++i) {
    if (const auto* t = std::get_if<PublishTally>(&actions[i]); t && t->episode == 0) {
      last_tally0 = i;
    }
    if (const auto* m = std::get_if<PublishMeasurement>(&actions[i]); m && m->episode == 1) {
      first_m1 = std::min(first_m1, i);
    }
  }
  ASSERT_LT(first_m1, actions.size()) << "episode 1 ran";
  EXPECT_LT(last_tally0, first_m1);
  // Between the two, no ready status (it runs on).
  for (std::size_t i = last_tally0; i < first_m1; ++i) {
    if (const auto* s = std::get_if<PublishSensorStatus>(&actions[i])) {
      EXPECT_NE(s->state, SensorState::Ready);
    }
  }
  EXPECT_EQ(only<PublishTally>(actions).size(), 4U) << "two sensors, two episodes";
}

TEST_F(SensorAgentCoreTest, ItsOwnStallIsNotLagButATickThatComesLateIs) {
  const std::int64_t start = startEpisodeZero();
  // Ticks every 0.4 s (under the 0.5 s stall slack): each measurement waits up to 0.4 s.
  const SensorAgentActions slow = runUntil(start + 2 * kSecond, 4 * kSecond / 10);
  const auto slow_tallies = only<PublishTally>(slow);
  ASSERT_EQ(slow_tallies.size(), 2U);
  EXPECT_GT(slow_tallies[0].max_lag_s, 0.2) << "some measurement waited most of a tick";
  EXPECT_LE(slow_tallies[0].max_lag_s, 0.4 + 1e-9);
  EXPECT_DOUBLE_EQ(slow_tallies[0].stalled_s, 0.0);

  // Episode 1: one tick before it, then nothing for 1.5 s (SIGSTOP): what fell due goes out at
  // once, the stall is left out of the lag and reported as stalled time.
  const std::int64_t start1 = now_ + kSecond / 10;
  control(sensornet_EPISODE_START, 1, start1);
  (void)feed();
  (void)core_.tick(now_ += kSecond / 20);  // the episode begins for the agent
  now_ = start1 + 15 * kSecond / 10;
  const SensorAgentActions after = core_.tick(now_);
  EXPECT_TRUE(logs(after, "stalled for 1.55 s"));
  // Past T by then: the whole episode goes out at once, and its tallies.
  EXPECT_GT(only<PublishMeasurement>(after).size(), 10U);
  const auto tallies = only<PublishTally>(after);
  ASSERT_EQ(tallies.size(), 2U);
  EXPECT_LT(tallies[0].max_lag_s, 0.01) << "the stall is not lag";
  // Stalled from the last tick (0.05 s before the start) on: 1.5 s of the episode's time.
  EXPECT_NEAR(tallies[0].stalled_s, 1.5, 1e-9);
}

TEST_F(SensorAgentCoreTest, AStartTheNetworkDeliveredLateIsNotLag) {
  announceScenario();
  announceVersion(1, 0, 0.0, Eigen::MatrixXd::Constant(2, 3, 20.0));
  discover();
  (void)feed();
  // The start reaches the agent 0.6 s after the episode began.
  const std::int64_t start = now_ - 6 * kSecond / 10;
  control(sensornet_EPISODE_START, 0, start);
  const SensorAgentActions learned = feed();
  const SensorAgentActions first = core_.tick(now_ + 1);
  EXPECT_TRUE(logs(first, "its start reached this process 0.600 s after it began"));
  EXPECT_GT(only<PublishMeasurement>(first).size(), 5U) << "what fell due meanwhile, at once";
  const auto tallies = only<PublishTally>(runUntil(start + 2 * kSecond, kSecond / 1000));
  ASSERT_EQ(tallies.size(), 2U);
  EXPECT_LT(tallies[0].max_lag_s, 0.002);
  (void)learned;
}

TEST_F(SensorAgentCoreTest, ADelayedMeasurementGoesOutAtItsDelayAndTheTallyWaitsForIt) {
  const std::int64_t start = startEpisodeZero(kDelayedYaml, Eigen::MatrixXd::Constant(2, 3, 20.0));
  std::vector<Sent> sent;
  const SensorAgentActions actions = runUntil(start + 3 * kSecond, kSecond / 1000, &sent);
  ASSERT_FALSE(sent.empty());
  std::int64_t last_sent = 0;
  for (const Sent& s : sent) {
    const HeldMeasurement& m = s.what.measurement;
    EXPECT_DOUBLE_EQ(m.delay_s, 0.3);
    const std::int64_t due = start + static_cast<std::int64_t>(1e9 * (m.time_s + 0.3));
    EXPECT_GE(s.at_ns, due);
    EXPECT_LT(s.at_ns - kSecond / 1000, due);
    last_sent = std::max(last_sent, s.at_ns);
  }
  const auto tallies = only<PublishTally>(actions);
  ASSERT_EQ(tallies.size(), 2U);
  EXPECT_GE(tallies[0].wall_time_ns, last_sent) << "after the last held measurement";
  EXPECT_GT(tallies[0].wall_time_ns, start + kSecond) << "past T: the line held some";
}

TEST_F(SensorAgentCoreTest, AStoppedEpisodeFlushesWhatTheNetworkHeldAndTalliesUnfinished) {
  const std::int64_t start = startEpisodeZero(kDelayedYaml, Eigen::MatrixXd::Constant(2, 3, 20.0));
  std::vector<Sent> sent;
  (void)runUntil(start + kSecond / 2, kSecond / 1000, &sent);
  control(sensornet_EPISODE_STOP, 0, 0);
  const SensorAgentActions stop = feed();
  EXPECT_TRUE(logs(stop, "episode 0 ended early: stopped"));
  const auto flushed = only<PublishMeasurement>(stop);
  EXPECT_FALSE(flushed.empty()) << "0.3 s of held measurements";
  const auto tallies = only<PublishTally>(stop);
  ASSERT_EQ(tallies.size(), 2U);
  std::map<int, std::uint64_t> written;
  for (const Sent& s : sent) ++written[s.what.measurement.sensor];
  for (const auto& m : flushed) ++written[m.measurement.sensor];
  for (const PublishTally& t : tallies) {
    EXPECT_FALSE(t.finished);
    EXPECT_EQ(t.sent, written[t.sensor]) << "every drawn arrival was written";
  }
}

TEST_F(SensorAgentCoreTest, AFailedSensorPublishesNothingAndHasNoTally) {
  const std::int64_t start = startEpisodeZero(kYaml, Eigen::MatrixXd::Constant(2, 3, 20.0), {2});
  std::vector<Sent> sent;
  const SensorAgentActions actions = runUntil(start + 2 * kSecond, kSecond / 1000, &sent);
  EXPECT_TRUE(logs(actions, "sensor 2 was declared failed"));
  ASSERT_FALSE(sent.empty());
  for (const Sent& s : sent) EXPECT_EQ(s.what.measurement.sensor, 0);
  const auto tallies = only<PublishTally>(actions);
  ASSERT_EQ(tallies.size(), 1U);
  EXPECT_EQ(tallies[0].sensor, 0);
  EXPECT_EQ(core_.liveSensors(), std::vector<int>{0});
}

TEST_F(SensorAgentCoreTest, AScriptedCrashComesAtItsInstantAfterWhatWasDueAndNothingFollows) {
  const std::string crashing =
      kYaml + "faults:\n  - {kind: crash, sensor: 2, episode: 0, at: 0.5}\n";
  const std::int64_t start = startEpisodeZero(crashing, Eigen::MatrixXd::Constant(2, 3, 20.0));
  std::vector<Sent> sent;
  const SensorAgentActions actions = runUntil(start + 2 * kSecond, kSecond / 1000, &sent);
  ASSERT_TRUE(contains<CrashProcess>(actions));
  EXPECT_TRUE(std::holds_alternative<CrashProcess>(actions.back())) << "the crash is the last";
  EXPECT_TRUE(logs(actions, "scripted crash of sensor 2 at 0.5 s of episode 0"));
  EXPECT_TRUE(only<PublishTally>(actions).empty()) << "killed: no tally";
  ASSERT_FALSE(sent.empty());
  for (const Sent& s : sent) EXPECT_LE(s.what.measurement.time_s, 0.5);
  EXPECT_GT(sent.back().what.measurement.time_s, 0.3) << "what was due before it went out";
  EXPECT_EQ(core_.exitCode(), 1);
  EXPECT_TRUE(core_.tick(now_ + kSecond).empty());
}

TEST_F(SensorAgentCoreTest, ShutdownLeavesWithAcknowledgedWritesASignalWithout) {
  const std::int64_t start = startEpisodeZero();
  (void)runUntil(start + 2 * kSecond, kSecond / 100);
  control(sensornet_RUN_SHUTDOWN, 1, 0);
  const SensorAgentActions end = feed();
  const auto statuses = only<PublishSensorStatus>(end);
  ASSERT_EQ(statuses.size(), 2U);
  EXPECT_EQ(statuses[0].state, SensorState::Stopped);
  EXPECT_EQ(statuses[0].detail, "run shut down");
  const auto leave = only<LeaveRun>(end);
  ASSERT_EQ(leave.size(), 1U);
  EXPECT_EQ(leave[0].exit_code, 0) << "the run ended: exit 0";
  EXPECT_TRUE(leave[0].flush);
  EXPECT_EQ(core_.exitCode(), 0);

  SensorAgentCore other({{1}, 1.0}, inputs_);
  (void)other.start(now_);
  const SensorAgentActions signal = other.onStopSignal(now_);
  const auto left = only<LeaveRun>(signal);
  ASSERT_EQ(left.size(), 1U);
  EXPECT_EQ(left[0].exit_code, 1) << "stopped before the run ended: exit 1";
  EXPECT_FALSE(left[0].flush);
  EXPECT_EQ(only<PublishSensorStatus>(signal).at(0).detail, "stopped by a signal");
}

TEST_F(SensorAgentCoreTest, ASensorIdTheScenarioDoesNotHaveIsBadInput) {
  SensorAgentCore wide({{0, 3}, 1.0}, inputs_);
  announceScenario();
  inputs_.releaseStarts(update_);
  try {
    (void)wide.onInputs(update_, now_);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("ids below the scenario's M = 3, got 3"),
              std::string::npos)
        << e.what();
  }
}

// Driven as the executable drives it (wait as long as the core says, then tick), every
// measurement goes out at its instant and the tally at T, none late.
TEST_F(SensorAgentCoreTest, WaitingAsLongAsItSaysPublishesEachMeasurementOnTime) {
  EXPECT_EQ(core_.untilNextEvent(now_, kIdle), kIdle) << "no episode: the idle wait";
  const std::int64_t start = startEpisodeZero();
  std::vector<Sent> sent;
  SensorAgentActions all;
  int ticks = 0;
  while (only<PublishTally>(all).empty() && ticks < 10'000) {
    // A due instant rounded to the nanosecond may be reached one nanosecond later.
    now_ += std::max<std::int64_t>(1, core_.untilNextEvent(now_, kIdle).count());
    ++ticks;
    for (SensorAgentAction& a : core_.tick(now_)) {
      if (const auto* m = std::get_if<PublishMeasurement>(&a)) sent.push_back({now_, *m});
      all.push_back(std::move(a));
    }
  }
  ASSERT_FALSE(only<PublishTally>(all).empty());
  ASSERT_FALSE(sent.empty());
  for (const Sent& s : sent) {
    const std::int64_t due = start + static_cast<std::int64_t>(1e9 * s.what.measurement.time_s);
    EXPECT_GE(s.at_ns, due);
    EXPECT_LE(s.at_ns - due, 1'000) << "within a microsecond of its instant";
  }
  EXPECT_LE(only<PublishTally>(all)[0].wall_time_ns - (start + kSecond), 1'000);
  // Idle waits of 100 ms and one wake per arrival instant, not a busy loop.
  EXPECT_LT(ticks, static_cast<int>(3 * sent.size()) + 30);
}

}  // namespace
}  // namespace sensornet::emulator
