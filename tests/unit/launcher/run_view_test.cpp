// The follower core of `watch`, `status` and the launcher's progress lines, driven by scripted
// orders of events on a fake wall clock. Expectations come from the episode's life
// (docs/ARCHITECTURE.md: the next episode is announced while the current one runs; sensors say
// "stopped" when the run shuts down) and closed forms of the clock (t = (now - start) * scale),
// never from the view's own earlier output.

#include "sensornet/launcher/run_view.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

namespace sensornet::launcher {
namespace {

using emulator::SensorState;

constexpr std::int64_t kSecond = 1'000'000'000;
constexpr std::int64_t kT0 = 1'700'000'000 * kSecond;  // the fake wall clock's origin
constexpr double kHorizon = 3.0;
constexpr std::uint32_t kSensors = 6;

ScenarioSeen scenario() { return {"0123456789abcdef", kSensors, 4, kHorizon, 7}; }
ScheduleSeen version1() { return {1, "cov", 0, 0.0, 10.0, 30.0}; }

EpisodeAnnounced start(std::uint32_t episode, std::int64_t start_ns, double scale = 1.0,
                       std::uint32_t planned = 3) {
  return {episode, {start_ns, scale}, planned, 1};
}

SensorStatusSeen status(std::uint32_t sensor, SensorState state, std::int64_t said_ns,
                        std::string detail = "") {
  SensorStatusSeen s;
  s.sensor_id = sensor;
  s.state = state;
  s.schedule_version = 1;
  s.wall_time_ns = said_ns;
  s.detail = std::move(detail);
  return s;
}

EpisodeReportSeen report(std::uint32_t episode, bool complete = true) {
  EpisodeReportSeen r;
  r.episode = episode;
  r.realized_cost = 12.5 + episode;  // episode 13: 25.5
  r.complete = complete;
  r.counts = {{0, 10, complete ? 10u : 7u, 0}, {1, 5, 5, 0}};  // 15 sent, 12 or 15 received
  r.summary.episodes = episode + 1;
  r.summary.episodes_complete = episode + 1;
  r.summary.realized_mean = 12.5;
  r.summary.bracket_lower_mean = 10.0;
  r.summary.bracket_upper_mean = 30.0;
  r.summary.delivered_lower_mean = 10.0;  // nothing lost on the way
  r.summary.delivered_upper_mean = 30.0;
  return r;
}

bool has(const std::vector<std::string>& lines, const std::string& text) {
  return std::any_of(lines.begin(), lines.end(),
                     [&](const std::string& l) { return l.find(text) != std::string::npos; });
}

std::string joined(const std::vector<std::string>& lines) {
  std::string text;
  for (const std::string& l : lines) text += l + "\n";
  return text;
}

RunViewConfig named(const std::string& run_id, std::int64_t end_grace_ns = 3 * kSecond) {
  RunViewConfig config;
  config.run_id = run_id;
  config.end_grace_ns = end_grace_ns;
  return config;
}

// A run that has started: scenario, version 1, every sensor ready.
RunView runningView(std::int64_t now) {
  RunView view(named("run-1"));
  view.onScenario(scenario(), now);
  view.onSchedule(version1(), now);
  for (std::uint32_t j = 0; j < kSensors; ++j)
    view.onSensorStatus(status(j, SensorState::Ready, now), now);
  return view;
}

// At time scale 1 the coordinator announces episode 1 while episode 0 runs; the progress is
// episode 0's clock until episode 1's start has come (the bar stood at "starts soon" before).
TEST(RunView, ProgressFollowsTheRunningEpisodeWhileTheNextIsAnnouncedAhead) {
  RunView view = runningView(kT0);
  const std::int64_t start0 = kT0 + kSecond / 5;
  view.onEpisodeStart(start(0, start0), kT0);
  EXPECT_EQ(view.progressAt(kT0).phase, EpisodePhase::StartsSoon);
  EXPECT_NEAR(view.progressAt(kT0).starts_in_s, 0.2, 1e-9);

  const std::int64_t start1 = start0 + 3 * kSecond + kSecond / 5;  // horizon 3 s, gap 0.2 s
  view.onEpisodeStart(start(1, start1), start0 + kSecond / 2);     // announced ahead
  const std::int64_t now = start0 + 3 * kSecond / 2;
  const EpisodeProgress at = view.progressAt(now);
  EXPECT_EQ(at.phase, EpisodePhase::Running);
  ASSERT_TRUE(at.episode.has_value());
  EXPECT_EQ(*at.episode, 0u);
  EXPECT_NEAR(at.t_s, 1.5, 1e-9);  // (now - start) * scale
  EXPECT_EQ(view.positionAt(now).episode, std::optional<std::uint32_t>(0));
  EXPECT_NEAR(view.positionAt(now).emulated_time_s.value_or(-1), 1.5, 1e-9);
  EXPECT_NE(view.screen(now).find("t = 1.5 / 3 s"), std::string::npos) << view.screen(now);

  // Past its horizon, before the next start: episode 0 is over, episode 1 starts in 0.1 s.
  const EpisodeProgress between = view.progressAt(start1 - kSecond / 10);
  EXPECT_EQ(between.phase, EpisodePhase::Closing);
  EXPECT_EQ(*between.episode, 0u);
  EXPECT_NEAR(between.starts_in_s, 0.1, 1e-9);
  EXPECT_FALSE(view.positionAt(start1 - kSecond / 10).emulated_time_s.has_value());

  const EpisodeProgress next = view.progressAt(start1 + kSecond);
  EXPECT_EQ(*next.episode, 1u);
  EXPECT_NEAR(next.t_s, 1.0, 1e-9);
}

TEST(RunView, ProgressRunsOnTheEpisodesTimeScale) {
  RunView view = runningView(kT0);
  view.onEpisodeStart(start(0, kT0, 10.0), kT0);
  EXPECT_NEAR(view.progressAt(kT0 + kSecond / 4).t_s, 2.5, 1e-9);
}

// The run shut down: each sensor says "stopped" when it leaves, not all in the same poll. The
// view waits for every sensor's last word and puts the alike ones on one line.
TEST(RunView, EndsOnlyOnceEverySensorHasSaidItsLastAndListsThemAll) {
  RunView view = runningView(kT0);
  view.onEpisodeStart(start(0, kT0, 10.0, 1), kT0);
  view.onReport(report(0), kT0 + kSecond);
  (void)view.takeLines(kT0 + kSecond);
  const std::int64_t end = kT0 + 2 * kSecond;
  view.onRunEnd({1, false, ""}, end);
  for (std::uint32_t j = 0; j < 5; ++j) {
    view.onSensorStatus(status(j, SensorState::Stopped, end, "run shut down"), end);
  }
  EXPECT_FALSE(view.finished(end + kSecond / 10)) << "sensor 5 has not said it stopped";
  const std::vector<std::string> early = view.takeLines(end + kSecond / 10);
  EXPECT_FALSE(has(early, "run ended")) << joined(early);
  view.onSensorStatus(status(5, SensorState::Stopped, end + kSecond / 5, "run shut down"),
                      end + kSecond / 5);
  EXPECT_TRUE(view.finished(end + kSecond / 5));
  const std::vector<std::string> lines = view.takeLines(end + kSecond / 5);
  EXPECT_TRUE(has(lines, "sensors 0, 1, 2, 3, 4, 5: stopped under schedule v1: run shut down"))
      << joined(lines);
  EXPECT_TRUE(has(lines, "run ended: 1 episode(s), 1 reported")) << joined(lines);
  for (const auto& [id, s] : view.sensors()) EXPECT_EQ(s.state, SensorState::Stopped) << id;
  EXPECT_TRUE(view.endedCleanly());
}

TEST(RunView, AStoppedSensorsProcessLeavingIsNoNews) {
  RunView view = runningView(kT0);
  view.onRunEnd({0, false, ""}, kT0);
  for (std::uint32_t j = 0; j < kSensors; ++j) {
    view.onSensorStatus(status(j, SensorState::Stopped, kT0 + 1, "run shut down"), kT0 + 1);
  }
  for (std::uint32_t j = 0; j < kSensors; ++j) view.onSensorGone(j, kT0 + 2);
  const std::vector<std::string> lines = view.takeLines(kT0 + 3 * kSecond);
  EXPECT_TRUE(has(lines, "sensors 0, 1, 2, 3, 4, 5: stopped under schedule v1: run shut down"))
      << joined(lines);
  EXPECT_FALSE(has(lines, "gone")) << joined(lines);
}

TEST(RunView, ASensorWhoseProcessIsGoneNeedsNoLastWord) {
  RunView view = runningView(kT0);
  view.onRunEnd({0, false, ""}, kT0);
  for (std::uint32_t j = 0; j < kSensors; ++j) {
    if (j == 2) {
      view.onSensorGone(j, kT0);
    } else {
      view.onSensorStatus(status(j, SensorState::Stopped, kT0), kT0);
    }
  }
  EXPECT_TRUE(view.finished(kT0));
}

// Nothing more comes: the end grace bounds the wait for the last words and reports.
TEST(RunView, TheEndGraceBoundsTheWaitForMissingReports) {
  RunView view = runningView(kT0);
  view.onRunEnd({3, false, ""}, kT0);
  for (std::uint32_t j = 0; j < kSensors; ++j) {
    view.onSensorStatus(status(j, SensorState::Stopped, kT0), kT0);
  }
  view.onReport(report(0), kT0);
  EXPECT_FALSE(view.finished(kT0 + kSecond)) << "2 of 3 reports are missing";
  EXPECT_TRUE(view.finished(kT0 + 3 * kSecond));
  EXPECT_TRUE(has(view.takeLines(kT0 + 3 * kSecond), "run ended: 3 episode(s), 1 reported"));
}

// A watcher that joins late gets the transient-local reports before it has the scenario or the
// planned count: they wait, and come after the scenario's line, numbered "[k/N]".
TEST(RunView, ReportsThatCameFirstWaitForTheScenarioAndThePlannedCount) {
  RunView view(named("run-1"));
  view.onReport(report(1), kT0);
  view.onReport(report(0), kT0);
  EXPECT_TRUE(view.takeLines(kT0).empty()) << "nothing before the scenario's line";
  view.onScenario(scenario(), kT0);
  view.onSchedule(version1(), kT0);
  const std::vector<std::string> head = view.takeLines(kT0);
  ASSERT_FALSE(head.empty());
  EXPECT_EQ(head.front().rfind("run run-1: scenario 0123456789ab, 6 sensors", 0), 0u)
      << joined(head);
  EXPECT_FALSE(has(head, "episode 0:")) << "the planned count is not known yet";
  view.onEpisodeStart(start(2, kT0 + kSecond / 5, 1.0, 5), kT0);
  const std::vector<std::string> lines = view.takeLines(kT0);
  ASSERT_EQ(lines.size(), 3u) << joined(lines);
  EXPECT_EQ(lines[0].rfind("[1/5] episode 0: realized 12.5", 0), 0u) << joined(lines);
  EXPECT_EQ(lines[1].rfind("[2/5] episode 1: realized 13.5", 0), 0u) << joined(lines);
  EXPECT_EQ(lines[2], "[3/5] episode 2 started (schedule v1, time scale 1)");
  EXPECT_EQ(view.episodesReported(), 2u);
}

TEST(RunView, ReportsBeforeTheScenarioAreSaidWhenTheRunEndsWithoutOne) {
  RunView view(named("run-1", 0));
  view.onReport(report(0), kT0);
  view.onCoordinatorGone(kT0);
  const std::vector<std::string> lines = view.takeLines(kT0);
  EXPECT_TRUE(has(lines, "[1/?] episode 0: realized 12.5")) << joined(lines);
  EXPECT_TRUE(has(lines, "coordinator left without shutting the run down")) << joined(lines);
  EXPECT_FALSE(view.endedCleanly());
}

// One convention: the episode's own number (0-based, as in report.json), its place [k/N] with
// k = episode + 1, on the start line and the report line alike.
TEST(RunView, StartAndReportLinesNumberAnEpisodeAlike) {
  RunView view = runningView(kT0);
  (void)view.takeLines(kT0);
  view.onEpisodeStart(start(13, kT0 + kSecond / 5, 1.0, 25), kT0);
  view.onReport(report(13), kT0 + 4 * kSecond);
  const std::vector<std::string> lines = view.takeLines(kT0 + 4 * kSecond);
  EXPECT_TRUE(has(lines, "[14/25] episode 13 started")) << joined(lines);
  EXPECT_TRUE(has(lines, "[14/25] episode 13: realized 25.5")) << joined(lines);
  EXPECT_FALSE(has(lines, "of 25")) << joined(lines);
}

// A Report's latency is the run's so far; none (0) when the fusion center has none it believes
// (nothing measured, or clocks it found apart): said so, never "median 0 ms".
TEST(RunView, AReportWithoutLatencySaysItIsNotKnown) {
  RunView view = runningView(kT0);
  (void)view.takeLines(kT0);
  view.onEpisodeStart(start(0, kT0 + kSecond / 5, 1.0, 2), kT0);
  view.onEpisodeStart(start(1, kT0 + kSecond, 1.0, 2), kT0);
  EpisodeReportSeen measured = report(0);
  measured.latency_median_s = 2.5e-4;
  measured.latency_p99_s = 1e-3;
  view.onReport(measured, kT0 + kSecond);
  view.onReport(report(1), kT0 + 2 * kSecond);
  const std::vector<std::string> lines = view.takeLines(kT0 + 2 * kSecond);
  EXPECT_TRUE(has(lines, "episode 0: realized 12.5")) << joined(lines);
  EXPECT_TRUE(has(lines, "latency median 0.25 ms, p99 1 ms")) << joined(lines);
  EXPECT_TRUE(has(lines, "episode 1: realized 13.5")) << joined(lines);
  EXPECT_TRUE(has(lines, "latency not known")) << joined(lines);
  EXPECT_FALSE(has(lines, "median 0 ms")) << joined(lines);
}

TEST(RunView, AReplayedStartOfAnEpisodeThatIsOverIsNotNews) {
  RunView view = runningView(kT0 + 100 * kSecond);
  (void)view.takeLines(kT0 + 100 * kSecond);
  view.onEpisodeStart(start(4, kT0), kT0 + 100 * kSecond);  // ended at kT0 + 3 s
  view.onEpisodeStart(start(5, kT0 + 99 * kSecond), kT0 + 100 * kSecond);
  const std::vector<std::string> lines = view.takeLines(kT0 + 100 * kSecond);
  EXPECT_FALSE(has(lines, "episode 4 started")) << joined(lines);
  EXPECT_TRUE(has(lines, "episode 5 started")) << joined(lines);
}

// A late watcher may get the replayed starts before the scenario (other topics): they wait for
// its horizon, and those of episodes over by now are left out.
TEST(RunView, StartsBeforeTheScenarioAreSaidOnlyIfTheirEpisodeIsNotOver) {
  const std::int64_t now = kT0 + 100 * kSecond;
  RunView view(named("run-1"));
  view.onEpisodeStart(start(4, kT0, 1.0, 9), now);            // over at kT0 + 3 s
  view.onEpisodeStart(start(5, now - kSecond, 1.0, 9), now);  // runs
  view.onScenario(scenario(), now);
  const std::vector<std::string> lines = view.takeLines(now);
  ASSERT_EQ(lines.size(), 2u) << joined(lines);
  EXPECT_EQ(lines[0].rfind("run run-1: scenario", 0), 0u) << joined(lines);
  EXPECT_EQ(lines[1], "[6/9] episode 5 started (schedule v1, time scale 1)");
}

TEST(RunView, AReportIsTakenOnce) {
  RunViewConfig config;  // the launcher's
  config.episodes_planned = 3;
  config.keep_lines = false;
  config.keep_reports = true;
  RunView view(config);
  view.onReport(report(0), kT0);
  view.onReport(report(0), kT0);
  view.onReport(report(1), kT0);
  EXPECT_EQ(view.takeReports().size(), 2u) << "the launcher needs no scenario line";
  view.onReport(report(1), kT0);
  EXPECT_TRUE(view.takeReports().empty());
  EXPECT_EQ(view.episodesReported(), 2u);
}

TEST(RunView, ProgressLineSaysWhyAnEpisodeIsIncomplete) {
  EpisodeReportSeen r = report(1, /*complete=*/false);
  r.incomplete_reason = "sensor 1 failed at 0.202 s";
  const std::string line = formatProgress(r, 3);
  EXPECT_NE(line.find("INCOMPLETE (sensor 1 failed at 0.202 s): 12 of 15 sent measurements"),
            std::string::npos)
      << line;
  EXPECT_EQ(line.rfind("[2/3] episode 1: realized 13.5", 0), 0u) << line;
}

// After a death under `continue` (or on a lossy network) the line shows, beside the planned
// bracket, what the schedule could deliver; with nothing lost on the way only the plan.
TEST(RunView, ProgressLineShowsTheDeliveredBracketBesideThePlannedOne) {
  EpisodeReportSeen r = report(3);
  EXPECT_EQ(formatProgress(r, 6).find("delivered"), std::string::npos) << formatProgress(r, 6);
  r.summary.delivered_lower_mean = 10.93;
  r.summary.delivered_upper_mean = 74.85;
  const std::string line = formatProgress(r, 6);
  EXPECT_NE(line.find("bracket [10, 30] (delivered [10.93, 74.85])"), std::string::npos) << line;
}

TEST(RunView, ProgressLineWithoutACompleteEpisodeShowsNoMean) {
  EpisodeReportSeen r = report(0, /*complete=*/false);
  r.summary.episodes_complete = 0;
  r.summary.realized_mean = 0.0;
  const std::string line = formatProgress(r, 3);
  EXPECT_EQ(line.find("mean"), std::string::npos) << line;
  EXPECT_NE(line.find("no complete episode yet"), std::string::npos) << line;
}

TEST(RunView, EverySensorIsAccountedForWhenAnsweredOrKnownDead) {
  RunView view(named("run-1"));
  view.onScenario(scenario(), kT0);
  for (std::uint32_t j = 0; j < kSensors - 1; ++j) {
    view.onSensorStatus(status(j, SensorState::Running, kT0), kT0);
  }
  EXPECT_FALSE(view.allSensorsAccounted());
  view.onSensorsFailed({0, 0.5, {5}, "killed by signal 9"}, kT0);
  EXPECT_TRUE(view.allSensorsAccounted());
  EXPECT_TRUE(view.sensors().at(5).failed);
}

TEST(RunView, AnOlderStatusOfAnotherWriterDoesNotOverwriteANewerOne) {
  RunView view = runningView(kT0);
  view.onSensorStatus(status(0, SensorState::Running, kT0 + 2 * kSecond), kT0 + 2 * kSecond);
  view.onSensorStatus(status(0, SensorState::Ready, kT0 + kSecond), kT0 + 2 * kSecond);
  EXPECT_EQ(view.sensors().at(0).state, SensorState::Running);
}

TEST(RunView, TheCoordinatorLeavingEndsTheRunUncleanly) {
  RunView view = runningView(kT0);
  view.onEpisodeStart(start(0, kT0), kT0);
  view.onCoordinatorGone(kT0 + kSecond);
  EXPECT_TRUE(view.ended());
  EXPECT_FALSE(view.endedCleanly());
  // The sensors still run the episode on its clock.
  EXPECT_EQ(view.progressAt(kT0 + kSecond).phase, EpisodePhase::Running);
  EXPECT_EQ(view.positionAt(kT0 + kSecond).episode, std::optional<std::uint32_t>(0));
  EXPECT_FALSE(view.finished(kT0 + kSecond)) << "the sensors are still there";
  EXPECT_TRUE(view.finished(kT0 + 4 * kSecond));
}

// The launcher restarts a killed coordinator: its next announcement means the run goes on.
TEST(RunView, ARestartedCoordinatorsAnnouncementRevivesTheRun) {
  RunView view = runningView(kT0);
  view.onEpisodeStart(start(0, kT0), kT0);
  view.onCoordinatorGone(kT0 + kSecond);
  view.onEpisodeStart(start(1, kT0 + 4 * kSecond), kT0 + 2 * kSecond);
  EXPECT_FALSE(view.ended());
  EXPECT_FALSE(view.finished(kT0 + 10 * kSecond));
  EXPECT_TRUE(has(view.takeLines(kT0 + 2 * kSecond), "the run's coordinator is back"));
  EXPECT_EQ(view.positionAt(kT0 + 5 * kSecond).episode, std::optional<std::uint32_t>(1));
}

}  // namespace
}  // namespace sensornet::launcher
