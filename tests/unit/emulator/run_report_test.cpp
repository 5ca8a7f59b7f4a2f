// The run report (sensornet/emulator/run_report.hpp): the summary of complete episodes with its
// Student t interval, nulls for what was not measured, the network's delay and drops, the
// bracket verdict, the report rebuilt from its episode log, and a restarted fusion center's
// resumed run.

#include "sensornet/emulator/run_report.hpp"

#include <gtest/gtest.h>

#include <sstream>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <vector>

#include "sensornet/emulator/episode_fusion.hpp"
#include "sensornet/report/report_files.hpp"
#include "support/scratch_dir.hpp"

namespace sensornet::emulator {
namespace {

using sensornet::report::EpisodeLog;
using sensornet::report::episodeLogPath;
using sensornet::report::readEpisodeLog;

using sensornet::testing::ScratchDir;

EpisodeResult episodeWith(std::uint32_t number, double cost, double info, bool complete) {
  EpisodeResult e;
  e.episode = number;
  e.realized_cost = cost;
  e.bracket = {info, 20.0};
  e.nees = 3.0;
  e.complete = complete;
  e.sensors.resize(2);
  e.sensors[0].sent = 5;
  e.sensors[0].received = 4;
  e.sensors[0].lost = 1;
  e.sensors[0].expected = 4.5;
  e.latencies_s = {0.001 * static_cast<double>(number + 1)};
  return e;
}

TEST(RunReport, SummarizesCompleteEpisodesWithAStudentTInterval) {
  RunReport report("r", "d", 2, 3);
  const std::vector<double> costs = {3.0, 5.0, 10.0, 2.0};
  for (std::size_t i = 0; i < costs.size(); ++i) {
    const EpisodeResult e =
        episodeWith(static_cast<std::uint32_t>(i), costs[i], 1.0 + static_cast<double>(i), true);
    report.addLatencies(e.latencies_s);
    report.add(episodeEntry(e));
  }
  // An incomplete episode counts in the totals, not in the statistics.
  report.add(episodeEntry(episodeWith(4, 1000.0, 1.0, false)));
  const RunSummary s = report.summary();
  EXPECT_EQ(s.episodes, 5u);
  EXPECT_EQ(s.episodes_complete, 4u);
  EXPECT_DOUBLE_EQ(s.mean, 5.0);
  EXPECT_NEAR(s.std_dev, std::sqrt((4.0 + 0.0 + 25.0 + 9.0) / 3.0), 1e-12);
  // t_{0.975, 3} = 3.18245 (tables), not 1.96.
  ASSERT_TRUE(s.ci95.has_value());
  EXPECT_NEAR(*s.ci95, 3.18245 * s.std_dev / 2.0, 1e-4);
  EXPECT_DOUBLE_EQ(s.bracket_mean.info, 2.5);
  EXPECT_EQ(s.meets_bracket, std::optional<bool>(true));
  EXPECT_EQ(s.sent, 25u);
  EXPECT_EQ(s.received, 20u);
  EXPECT_EQ(s.lost, 5u);
  EXPECT_DOUBLE_EQ(s.expected, 22.5);
  EXPECT_NEAR(s.latency_median_s, 0.0025, 0.0025 * kLatencyQuantileRelativeError);  // histogram
  EXPECT_DOUBLE_EQ(quantile({1.0, 2.0, 3.0, 4.0, 5.0}, 0.99), 4.96);
}

// Issue 31, finding 2: a run stopped before any episode completed reported 0.0 for the mean, the
// interval, the bracket and the latency; what was not measured is null.
// The NEES band of a 2-state filter over one complete episode is the closed form of chi-square(2)'s
// quantiles, [-2 ln(1 - 0.0005), -2 ln(0.0005)]: a NEES of 3 lies in it, one of 442 (the z = 0
// sensor of issue 48) does not; over two episodes the band is that of chi-square(4) / 2.
TEST(RunReport, SaysWhetherTheMeanNeesLiesInTheChiSquareBandOfAConsistentFilter) {
  RunReport report("r", "d", 2, 2);
  EpisodeResult e = episodeWith(0, 3.0, 1.0, true);
  report.add(episodeEntry(e));
  RunSummary s = report.summary();
  ASSERT_TRUE(s.nees_band && s.nees_consistent);
  EXPECT_NEAR(s.nees_band->low, -2.0 * std::log1p(-0.0005), 1e-12);
  EXPECT_NEAR(s.nees_band->high, -2.0 * std::log(0.0005), 1e-9);
  EXPECT_TRUE(*s.nees_consistent);
  e.episode = 1;
  e.nees = 442.0;
  report.add(episodeEntry(e));
  s = report.summary();
  ASSERT_TRUE(s.nees_consistent);
  EXPECT_FALSE(*s.nees_consistent);
  // chi-square(4) has P(X > x) = e^{-x/2} (1 + x/2): the band's top, over K = 2, solves it at 0.0005.
  const double top = 2.0 * s.nees_band->high;
  EXPECT_NEAR(std::exp(-0.5 * top) * (1.0 + 0.5 * top), 0.0005, 1e-12);
  const nlohmann::json doc = report.toJsonWithoutEpisodes("completed", nlohmann::json::array(),
                                                          nlohmann::json::array(), {});
  EXPECT_EQ(doc.at("summary").at("nees_consistent"), false);
  EXPECT_EQ(doc.at("summary").at("nees_confidence"), 0.999);
}

TEST(RunReport, WritesNullForWhatNoCompleteEpisodeMeasured) {
  using nlohmann::json;
  RunReport none("r", "d", 2, 3);
  const EpisodeResult cut = episodeWith(0, 931.5, 1.0, false);  // cut short: not in the statistics
  none.addLatencies(cut.latencies_s);
  none.add(episodeEntry(cut));
  json s = none.toJson("interrupted", json::array(), json::array()).at("summary");
  for (const char* key : {"mean", "std", "ci95", "ci95_low", "ci95_high", "realtime_mean",
                          "nees_mean", "bracket", "delivered_bracket", "meets_bracket"}) {
    EXPECT_TRUE(s.at(key).is_null()) << key << " = " << s.at(key);
  }
  const json latency = none.toJson("interrupted", json::array(), json::array()).at("latency_s");
  EXPECT_NEAR(latency.at("median").get<double>(), 0.001, 0.001 * kLatencyQuantileRelativeError);

  RunReport one("r", "d", 2, 3);
  one.add(episodeEntry(episodeWith(0, 19.59, 1.0, true)));
  s = one.toJson("completed", json::array(), json::array()).at("summary");
  EXPECT_DOUBLE_EQ(s.at("mean").get<double>(), 19.59);
  for (const char* key : {"std", "ci95", "ci95_low", "ci95_high"}) {
    EXPECT_TRUE(s.at(key).is_null()) << key << ": one complete episode has no spread";
  }
  EXPECT_TRUE(s.at("bracket").is_object());

  RunReport empty("r", "d", 2, 3);
  const json nothing = empty.toJson("interrupted", json::array(), json::array());
  EXPECT_TRUE(nothing.at("latency_s").at("median").is_null());
  EXPECT_TRUE(nothing.at("latency_s").at("p99").is_null());
}

// The emulated network's delay, apart from the latency: the mean over every received
// measurement (episode means weighted by what each received), and the largest.
TEST(RunReport, KeepsTheEmulatedNetworkDelayApartFromTheLatency) {
  RunReport report("r", "d", 2, 3);
  EpisodeResult a = episodeWith(0, 3.0, 1.0, true);  // received 4 (sensor 0) + 0
  a.network_delay_mean_s = 0.010;
  a.network_delay_max_s = 0.030;
  EpisodeResult b = episodeWith(1, 4.0, 1.0, true);
  b.sensors[1].sent = b.sensors[1].received = 4;  // received 8
  b.network_delay_mean_s = 0.040;
  b.network_delay_max_s = 0.090;
  report.add(episodeEntry(a));
  report.add(episodeEntry(b));
  const nlohmann::json delay = report.toJson("completed", {}, {}).at("network_delay_s");
  EXPECT_NEAR(delay.at("mean").get<double>(), (4 * 0.010 + 8 * 0.040) / 12.0, 1e-15);
  EXPECT_DOUBLE_EQ(delay.at("max").get<double>(), 0.090);
  EXPECT_TRUE(RunReport("r", "d", 2, 3)
                  .toJson("completed", {}, {})
                  .at("network_delay_s")
                  .at("mean")
                  .is_null());
}

// Ten expected counts of 0.1 add up to 0.9999999999999999 in doubles: the report says 1.
TEST(RunReport, ReportsTheExpectedTotalWithoutTheSummationsRoundingError) {
  RunReport report("r", "d", 2, 3);
  double direct = 0.0;
  for (std::uint32_t i = 0; i < 10; ++i) {
    EpisodeResult e = episodeWith(i, 3.0, 1.0, true);
    e.sensors[0].expected = 0.1;
    direct += 0.1;
    report.add(episodeEntry(e));
  }
  ASSERT_NE(direct, 1.0);
  EXPECT_EQ(report.toJson("completed", {}, {}).at("summary").at("expected").get<double>(), 1.0);
}

TEST(RunReport, CountsWhatTheNetworkDroppedPerEpisodePerSensorAndInTotal) {
  RunReport report("r", "d", 2, 3);
  for (std::uint32_t i = 0; i < 3; ++i) {
    EpisodeResult e = episodeWith(i, 2.0, 1.0, true);
    e.sensors[1].sent = 10 + i;
    e.sensors[1].received = 7;
    e.sensors[1].dropped_by_network = 3 + i;
    e.rejected[kNetworkDuplicate] = 2;
    report.add(episodeEntry(e));
  }
  const nlohmann::json doc =
      report.toJson("completed", nlohmann::json::array(), nlohmann::json::array());
  EXPECT_EQ(doc.at("per_episode").at(2).at("dropped_by_network"), nlohmann::json({0, 5}));
  EXPECT_EQ(doc.at("sensors").at(0).at("dropped_by_network"), 0);
  EXPECT_EQ(doc.at("sensors").at(1).at("dropped_by_network"), 12);
  EXPECT_EQ(doc.at("sensors").at(1).at("sent"), 33);
  EXPECT_EQ(doc.at("summary").at("dropped_by_network"), 12);
  EXPECT_EQ(doc.at("summary").at("rejected_by_reason").at(kNetworkDuplicate), 6);
  const RunSummary s = report.summary();
  EXPECT_EQ(s.sent, s.received + s.lost + s.dropped_by_network);
  EXPECT_EQ(faultyRejections(s.rejected), 0u);
}

// Costs 4, 5, 6 (mean 5, 95% interval 5 ± 4.30 * 1 / sqrt(3) = [2.52, 7.48]) against a planned
// bracket [1, 2] it misses and a delivered bracket [4, 6] it meets; an incomplete episode and
// an entry without a delivered bracket (an older log: the bracket stands in) as stated.
TEST(RunReport, SaysWhetherTheMeanMeetsTheDeliveredBracket) {
  RunReport report("r", "d", 2, 3);
  for (std::uint32_t i = 0; i < 3; ++i) {
    EpisodeResult e = episodeWith(i, 4.0 + i, 1.0, true);
    e.bracket = {1.0, 2.0};
    e.delivered_bracket = {3.0 + i, 5.0 + i};
    report.add(episodeEntry(e));
  }
  EpisodeResult incomplete = episodeWith(3, 100.0, 1.0, false);
  incomplete.delivered_bracket = {100.0, 200.0};
  report.add(episodeEntry(incomplete));
  RunSummary s = report.summary();
  EXPECT_DOUBLE_EQ(s.delivered_bracket_mean.info, 4.0);
  EXPECT_DOUBLE_EQ(s.delivered_bracket_mean.cov, 6.0);
  EXPECT_EQ(s.meets_bracket, std::optional<bool>(false));
  EXPECT_EQ(s.meets_delivered_bracket, std::optional<bool>(true));
  const nlohmann::json doc =
      report.toJson("completed", nlohmann::json::array(), nlohmann::json::array());
  EXPECT_EQ(doc.at("summary").at("delivered_bracket"),
            nlohmann::json({{"info", 4.0}, {"cov", 6.0}}));
  EXPECT_EQ(doc.at("summary").at("meets_delivered_bracket"), true);
  EXPECT_EQ(doc.at("per_episode").at(1).at("delivered_bracket").at("cov"), 6.0);

  nlohmann::json old = episodeEntry(episodeWith(4, 5.0, 1.0, true));
  old.erase("delivered_bracket");
  report.add(old);
  s = report.summary();
  EXPECT_DOUBLE_EQ(s.delivered_bracket_mean.info, (12.0 + 1.0) / 4.0);

  RunReport one("r", "d", 2, 3);
  one.add(episodeEntry(episodeWith(0, 3.0, 1.0, true)));
  EXPECT_TRUE(one.toJson("completed", nlohmann::json::array(), nlohmann::json::array())
                  .at("summary")
                  .at("meets_delivered_bracket")
                  .is_null());
}

TEST(RunReport, ClipsTheIntervalAtZeroAndLeavesOneEpisodeUndetermined) {
  RunReport two("r", "d", 2, 3);
  two.add(episodeEntry(episodeWith(0, 0.1, 1.0, true)));
  two.add(episodeEntry(episodeWith(1, 5.0, 1.0, true)));
  const RunSummary s = two.summary();
  // Mean 2.55, half-width 12.706 * 3.465 / sqrt(2) ~ 31: the low end would be negative.
  EXPECT_EQ(s.ci95_low, 0.0);
  EXPECT_NEAR(s.ci95_high, 2.55 + 12.7062 * std::sqrt(2.0 * 2.45 * 2.45) / std::sqrt(2.0), 1e-3);
  RunReport one("r", "d", 2, 3);
  one.add(episodeEntry(episodeWith(0, 3.0, 1.0, true)));
  EXPECT_FALSE(one.summary().ci95.has_value());
  EXPECT_FALSE(one.summary().meets_bracket.has_value());
  EXPECT_TRUE(one.toJson("completed", nlohmann::json::array(), nlohmann::json::array())
                  .at("summary")
                  .at("meets_bracket")
                  .is_null());
}

TEST(RunReport, RebuildsTheSameReportFromItsEpisodeLog) {
  const ScratchDir scratch;
  const std::filesystem::path& dir = scratch.path();
  const std::filesystem::path report_path = dir / "report.json";
  EXPECT_EQ(episodeLogPath(report_path), dir / "report.jsonl");
  EXPECT_EQ(episodeLogPath(dir / "out"), dir / "out.jsonl");
  RunReport report("r", "d", 2, 3);
  {
    EpisodeLog log(episodeLogPath(report_path));
    for (std::uint32_t i = 0; i < 3; ++i) {
      const nlohmann::json entry = episodeEntry(episodeWith(i, 2.0 + i, 1.0, i != 1));
      log.append(entry);
      report.add(entry);
    }
  }
  std::ofstream(episodeLogPath(report_path), std::ios::app) << "{\"episode\": 3, \"realiz";  // torn
  const auto entries = readEpisodeLog(episodeLogPath(report_path));
  ASSERT_EQ(entries.size(), 3u);
  const nlohmann::json rebuilt =
      reportFromEpisodes("r", 2, 3, entries, "failed", nlohmann::json::array());
  const nlohmann::json original =
      report.toJson("failed", nlohmann::json::array(), nlohmann::json::array());
  EXPECT_EQ(rebuilt.at("per_episode"), original.at("per_episode"));
  EXPECT_EQ(rebuilt.at("summary"), original.at("summary"));
  EXPECT_EQ(rebuilt.at("sensors"), original.at("sensors"));
  EXPECT_EQ(rebuilt.at("summary").at("episodes_incomplete"), 1);
}

// A full disk refuses the episode log from episode 2 on: the report holds episodes 2 and 3 itself,
// and per_episode is every episode once, in order, equal to a report that kept them all.
TEST(RunReport, HoldsWhatTheEpisodeLogRefusedAndReportsEveryEpisode) {
  const ScratchDir scratch;
  const std::filesystem::path log_path = scratch.path() / "report.jsonl";
  RunReport logged("r", "d", 2, 3, log_path);
  RunReport in_memory("r", "d", 2, 3);
  {
    EpisodeLog log(log_path);
    for (std::uint32_t i = 0; i < 4; ++i) {
      const nlohmann::json entry = episodeEntry(episodeWith(i, 2.0 + i, 1.0, i != 1));
      logged.add(entry);
      in_memory.add(entry);
      if (i < 2) log.append(entry);
      if (i == 2) logged.holdFrom(entry);  // refused: the core holds it, and what follows
    }
  }
  const nlohmann::json doc =
      logged.toJsonWithoutEpisodes("degraded", nlohmann::json::array(), nlohmann::json::array());
  std::ostringstream written;
  logged.write(written, doc, -1);
  const nlohmann::json expected =
      in_memory.toJson("degraded", nlohmann::json::array(), nlohmann::json::array());
  EXPECT_EQ(nlohmann::json::parse(written.str()).at("per_episode"), expected.at("per_episode"));
  EXPECT_EQ(readEpisodeLog(log_path).size(), 2u);
}

// A restarted fusion center: the log it died with (episodes 0, 2 and 3 finished, 1 was still
// waiting for a tally, a line torn mid-write) starts its report; it appends after it; episode 4,
// under way when it joined, and episode 1 are recorded as restarted; the rebuilt report has each
// episode once, the restarted ones incomplete with null costs.
TEST(ResumedRun, StartsFromTheEpisodeLogAndRecordsWhatItCouldNotFuse) {
  const ScratchDir scratch;
  const std::filesystem::path& dir = scratch.path();
  const std::filesystem::path log_path = dir / "report.jsonl";
  {
    EpisodeLog log(log_path);
    for (const std::uint32_t i : {0u, 2u, 3u})
      log.append(episodeEntry(episodeWith(i, 2.0 + i, 1.0, true)));
  }
  std::ofstream(log_path, std::ios::app) << "{\"episode\": 4, \"realiz";  // torn by the death

  const std::int64_t joined_ns = 1'000'000'000;
  ResumedRun resumed(readEpisodeLog(log_path), joined_ns);
  ASSERT_EQ(resumed.entries().size(), 3u);
  EXPECT_TRUE(resumed.ignores(2));
  EXPECT_FALSE(resumed.ignores(1));
  // The durable start heard on joining: episode 4 began before the join.
  EXPECT_EQ(resumed.heardStart(4, joined_ns - 500), (std::vector<std::uint32_t>{1, 4}));
  EXPECT_TRUE(resumed.ignores(4));
  EXPECT_TRUE(resumed.ignores(1));
  // The next episode starts after the join: fused here, and noted once it is.
  EXPECT_TRUE(resumed.heardStart(5, joined_ns + 10).empty());
  EXPECT_FALSE(resumed.ignores(5));
  resumed.noteFused(5);
  EXPECT_TRUE(resumed.heardEnd(7) == std::vector<std::uint32_t>{6});  // never heard of: lost too
  EXPECT_EQ(resumed.restarted(), (std::set<std::uint32_t>{1, 4, 6}));

  {
    EpisodeLog log(log_path, EpisodeLog::Mode::Append);
    EpisodeResult restarted = restartedEpisode(4, 2);
    restarted.versions = {1};
    restarted.bracket = {1.0, 20.0};
    log.append(episodeEntry(restarted));
    log.append(episodeEntry(episodeWith(5, 7.0, 1.0, true)));
  }
  const std::vector<nlohmann::json> entries = readEpisodeLog(log_path);
  ASSERT_EQ(entries.size(), 5u);  // 0, 2, 3, the restarted 4 and 5: the torn line is skipped
  const nlohmann::json& four = entries[3];
  EXPECT_EQ(four.at("episode"), 4);
  EXPECT_EQ(four.at("complete"), false);
  EXPECT_EQ(four.at("incomplete_reason"), kRestartedReason);
  EXPECT_TRUE(four.at("realized_cost").is_null());
  EXPECT_TRUE(four.at("realtime_cost").is_null());
  EXPECT_TRUE(four.at("delivered_bracket").at("info").is_null());
  EXPECT_EQ(four.at("bracket").at("cov"), 20.0);
  EXPECT_EQ(four.at("sent"), nlohmann::json({0, 0}));

  const nlohmann::json rebuilt =
      reportFromEpisodes("r", 2, 3, entries, "degraded", nlohmann::json::array());
  EXPECT_EQ(rebuilt.at("summary").at("episodes"), 5);
  EXPECT_EQ(rebuilt.at("summary").at("episodes_complete"), 4);
  EXPECT_DOUBLE_EQ(rebuilt.at("summary").at("mean").get<double>(), (2.0 + 4.0 + 5.0 + 7.0) / 4.0);
}

TEST(ResumedRun, AnEpisodeUnderWayThatItNeverSawStartIsRestartedOnce) {
  ResumedRun resumed({episodeEntry(episodeWith(0, 1.0, 1.0, true))}, 100);
  EXPECT_EQ(resumed.heardOfRunning(2), (std::vector<std::uint32_t>{1, 2}));
  EXPECT_TRUE(resumed.heardOfRunning(2).empty());
  EXPECT_TRUE(resumed.heardStart(2, 50).empty());  // its start, replayed later: already recorded
  EXPECT_TRUE(resumed.heardStart(3, 150).empty());
  EXPECT_FALSE(resumed.ignores(3));
}

}  // namespace
}  // namespace sensornet::emulator
