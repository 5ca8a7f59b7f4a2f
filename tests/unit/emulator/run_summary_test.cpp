// The run report's streaming summary (running sums, Welford, the latency histogram) against a
// direct computation over the same episodes held whole; the report streamed from its episode
// log against the whole document; EpisodeSet against std::set.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <random>
#include <set>
#include <sstream>
#include <unistd.h>
#include <vector>

#include "sensornet/core/student_t.hpp"
#include "sensornet/emulator/episode_set.hpp"
#include "sensornet/emulator/run_report.hpp"
#include "sensornet/report/report_files.hpp"
#include "support/scratch_dir.hpp"

namespace sensornet::emulator {
namespace {

using sensornet::report::EpisodeEntries;
using sensornet::report::EpisodeLog;
using sensornet::report::ReportFile;
using sensornet::report::readReport;

using nlohmann::json;

// The q-quantile by linear interpolation between order statistics, over sorted values.
double directQuantile(const std::vector<double>& sorted, double q) {
  const double position = q * static_cast<double>(sorted.size() - 1);
  const auto below = static_cast<std::size_t>(std::floor(position));
  const std::size_t above = std::min(below + 1, sorted.size() - 1);
  return sorted[below] + (position - static_cast<double>(below)) * (sorted[above] - sorted[below]);
}

// Episode `number` with a log-normal cost, 3 sensors' counts, and 1..40 latencies spread over
// four decades (log-normal around 100 us); every tenth is incomplete.
EpisodeResult randomEpisode(std::uint32_t number, std::mt19937_64& rng) {
  std::lognormal_distribution<double> cost(1.0, 0.5);
  std::lognormal_distribution<double> latency(std::log(1e-4), 1.2);
  std::uniform_int_distribution<int> samples(1, 40);
  std::uniform_int_distribution<std::uint64_t> count(0, 30);
  EpisodeResult e;
  e.episode = number;
  e.realized_cost = cost(rng);
  e.realtime_cost = e.realized_cost * 1.01;
  e.bracket = {0.5 * e.realized_cost, 2.0 * e.realized_cost};
  e.delivered_bracket = {0.6, 7.0};
  e.nees = 4.0 + 0.001 * number;
  e.complete = number % 10 != 7;
  if (!e.complete) e.incomplete_reason = "stall";
  e.sensors.resize(3);
  for (SensorTally& t : e.sensors) {
    t.received = count(rng);
    t.lost = count(rng) / 10;
    t.sent = t.received + t.lost;
    t.expected = 0.5 * static_cast<double>(t.sent);
  }
  e.latencies_s.resize(static_cast<std::size_t>(samples(rng)));
  for (double& l : e.latencies_s) l = latency(rng);
  return e;
}

// 3000 episodes (300 incomplete) and ~60,000 latencies: every statistic against its direct
// computation. Means to 1e-12 relative (Welford against a two-pass sum), counts exactly,
// median and p99 within LatencyHistogram's stated relative error, extremes exactly, and the
// coarse histogram equal to latencyHistogram() of every latency.
TEST(StreamingSummary, MatchesADirectComputationOverTheSameEpisodes) {
  std::mt19937_64 rng(20261130);
  RunReport report("r", "d", 3, 4);
  std::vector<double> costs, latencies;
  std::uint64_t sent = 0, lost = 0;
  double bracket_info = 0.0, nees = 0.0;
  const std::uint32_t episodes = 3000;
  for (std::uint32_t i = 0; i < episodes; ++i) {
    const EpisodeResult e = randomEpisode(i, rng);
    report.addLatencies(e.latencies_s);
    report.add(episodeEntry(e));
    latencies.insert(latencies.end(), e.latencies_s.begin(), e.latencies_s.end());
    for (const SensorTally& t : e.sensors) {
      sent += t.sent;
      lost += t.lost;
    }
    if (!e.complete) continue;
    costs.push_back(e.realized_cost);
    bracket_info += e.bracket.info;
    nees += e.nees;
  }
  const RunSummary s = report.summary();
  const double k = static_cast<double>(costs.size());
  const double mean = std::accumulate(costs.begin(), costs.end(), 0.0) / k;
  double squares = 0.0;
  for (const double c : costs) squares += (c - mean) * (c - mean);
  const double std_dev = std::sqrt(squares / (k - 1.0));
  EXPECT_EQ(s.episodes, episodes);
  EXPECT_EQ(s.episodes_complete, costs.size());
  EXPECT_EQ(s.sent, sent);
  EXPECT_EQ(s.lost, lost);
  EXPECT_NEAR(s.mean, mean, 1e-12 * mean);
  EXPECT_NEAR(s.std_dev, std_dev, 1e-10 * std_dev);
  ASSERT_TRUE(s.ci95.has_value());
  // t_{0.975, 2699} = 1.96084 (the normal's 1.95996 plus (z^3 + z) / (4 nu)).
  EXPECT_NEAR(*s.ci95, 1.96084 * std_dev / std::sqrt(k), 1e-4 * *s.ci95);
  EXPECT_NEAR(s.bracket_mean.info, bracket_info / k, 1e-12 * s.bracket_mean.info);
  EXPECT_NEAR(s.nees_mean, nees / k, 1e-12 * s.nees_mean);

  std::sort(latencies.begin(), latencies.end());
  for (const double q : {0.5, 0.99}) {
    const double exact = directQuantile(latencies, q);
    const double streamed = q == 0.5 ? s.latency_median_s : s.latency_p99_s;
    EXPECT_NEAR(streamed, exact, kLatencyQuantileRelativeError * exact) << "q = " << q;
    EXPECT_NE(streamed, exact) << "a histogram estimate is not expected to be exact";
  }
  const json doc = report.toJson("completed", json::array(), json::array());
  EXPECT_EQ(doc.at("latency_s").at("histogram"), latencyHistogram(latencies));
  EXPECT_EQ(doc.at("per_episode").size(), episodes);
  std::uint64_t sensor_sent = 0;
  for (const json& sensor : doc.at("sensors")) sensor_sent += sensor.at("sent").get<std::uint64_t>();
  EXPECT_EQ(sensor_sent, sent);
}

// Log-uniform latencies from 1 us to 10 s: every quantile (the extremes exact) within the
// stated bound; the bound is tight enough that a histogram of a tenth as many bins per decade
// would break it (the observed error reaches a fifth of it).
TEST(LatencyHistogram, QuantilesStayWithinTheStatedRelativeErrorAcrossDecades) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> exponent(-6.0, 1.0);
  std::vector<double> values(20001);
  LatencyHistogram h;
  for (double& v : values) {
    v = std::pow(10.0, exponent(rng));
    h.add(v);
  }
  std::sort(values.begin(), values.end());
  EXPECT_EQ(h.quantile(0.0), values.front());
  EXPECT_EQ(h.quantile(1.0), values.back());
  double worst = 0.0;
  for (int i = 1; i < 1000; ++i) {
    const double q = i / 1000.0;
    const double exact = directQuantile(values, q);
    const double error = std::abs(h.quantile(q) - exact) / exact;
    EXPECT_LE(error, kLatencyQuantileRelativeError) << "q = " << q;
    worst = std::max(worst, error);
  }
  EXPECT_GT(worst, 0.2 * kLatencyQuantileRelativeError);
  EXPECT_EQ(LatencyHistogram().quantile(0.5), 0.0);
  EXPECT_TRUE(LatencyHistogram().toJson().is_null());
}

// A report that holds no entry writes, from its episode log, the very text of the whole
// document (pretty and on one line): each episode once (a repeated line and a torn one are
// left out), in log order, with keys before and after per_episode.
TEST(RunReport, WritesPerEpisodeFromItsLogAsTheWholeDocumentWouldRead) {
  const sensornet::testing::ScratchDir scratch;
  const std::filesystem::path dir = scratch.path();
  ASSERT_FALSE(dir.empty());
  const std::filesystem::path log_path = dir / "report.jsonl";
  std::mt19937_64 rng(3);
  RunReport held("r", "d", 3, 4);
  RunReport streamed("r", "d", 3, 4, log_path);
  {
    EpisodeLog log(log_path);
    for (std::uint32_t i = 0; i < 40; ++i) {
      const EpisodeResult e = randomEpisode(i, rng);
      const json entry = episodeEntry(e);
      log.append(entry);
      if (i == 5) log.append(entry);  // a repeated line: the first counts
      held.add(entry);
      streamed.add(entry);
      held.addLatencies(e.latencies_s);
      streamed.addLatencies(e.latencies_s);
    }
  }
  std::ofstream(log_path, std::ios::app) << "{\"episode\": 40, \"realiz";  // torn
  const json faults = json::array({report::encode(faultEntry(FaultKind::Stall, "fusion_center", 1, 3, 0.5, "x"))});
  const json extra = {{"written_at", "2026-11-30T21:00:00Z"}, {"arrivals", {{"mode", "poisson"}}}};
  const json whole = held.toJson("degraded", faults, json::array(), extra);
  const json head = streamed.toJsonWithoutEpisodes("degraded", faults, json::array(), extra);
  EXPECT_FALSE(head.contains("per_episode"));
  for (const int indent : {2, -1}) {
    std::ostringstream out;
    streamed.write(out, head, indent);
    EXPECT_EQ(out.str(), whole.dump(indent)) << "indent " << indent;
  }
  EXPECT_EQ(streamed.toJson("degraded", faults, json::array(), extra), whole);

  RunReport empty("r", "d", 3, 4, dir / "none.jsonl");
  std::ostringstream out;
  empty.write(out, empty.toJsonWithoutEpisodes("completed", json::array(), json::array()), 2);
  EXPECT_EQ(json::parse(out.str()), empty.toJson("completed", json::array(), json::array()));
  EXPECT_EQ(json::parse(out.str()).at("per_episode"), json::array());
}

// The one reader of report files: a written report reads back whole, or without its
// per_episode (then nothing there is even looked at); anything else is one named problem.
TEST(ReportFile, ReadsAWrittenReportAndNamesWhatIsWrongWithAnythingElse) {
  const sensornet::testing::ScratchDir scratch;
  const std::filesystem::path dir = scratch.path();
  ASSERT_FALSE(dir.empty());
  std::mt19937_64 rng(5);
  RunReport report("r", "d", 3, 4);
  for (std::uint32_t i = 0; i < 6; ++i) report.add(episodeEntry(randomEpisode(i, rng)));
  const json doc = report.toJson("completed", json::array(), json::array());
  std::ofstream(dir / "report.json") << doc.dump(2);
  const ReportFile whole = readReport(dir / "report.json");
  ASSERT_TRUE(whole.ok());
  EXPECT_EQ(whole.report, doc);
  const ReportFile head = readReport(dir / "report.json", EpisodeEntries::Skipped);
  ASSERT_TRUE(head.ok());
  EXPECT_FALSE(head.report.contains("per_episode"));
  json expected = doc;
  expected.erase("per_episode");
  EXPECT_EQ(head.report, expected);

  EXPECT_EQ(readReport(dir / "absent.json").problem, ReportFile::Problem::Unreadable);
  std::ofstream(dir / "torn.json") << doc.dump().substr(0, 40);
  EXPECT_EQ(readReport(dir / "torn.json").problem, ReportFile::Problem::NotJson);
  const auto lacking = [&](const char* key) {
    json other = doc;
    other.erase(key);
    std::ofstream(dir / "other.json", std::ios::trunc) << other.dump();
    return readReport(dir / "other.json");
  };
  for (const char* key : {"run_id", "summary", "per_episode"}) {
    const ReportFile r = lacking(key);
    EXPECT_EQ(r.problem, ReportFile::Problem::NotAReport) << key;
    EXPECT_EQ(r.field, key);
    EXPECT_FALSE(r.expected.empty());
    EXPECT_TRUE(r.report.is_null()) << "no half-checked document is handed out";
  }
  std::ofstream(dir / "list.json") << "[1, 2]";
  EXPECT_EQ(readReport(dir / "list.json").problem, ReportFile::Problem::NotAReport);
  // Skipped, a per_episode of the wrong type is not looked at.
  json odd = doc;
  odd["per_episode"] = 3;
  std::ofstream(dir / "odd.json") << odd.dump();
  EXPECT_TRUE(readReport(dir / "odd.json", EpisodeEntries::Skipped).ok());
  EXPECT_EQ(readReport(dir / "odd.json").field, "per_episode");
}

// Random inserts (mostly in order, with gaps and repeats) against std::set.
TEST(EpisodeSet, AgreesWithAStdSetAndKeepsRangesDisjoint) {
  std::mt19937_64 rng(11);
  std::uniform_int_distribution<std::uint32_t> jitter(0, 6);
  EpisodeSet set;
  std::set<std::uint32_t> reference;
  for (std::uint32_t i = 0; i < 5000; ++i) {
    const std::uint32_t e = i + jitter(rng) - (i >= 3 ? 3 : 0);
    EXPECT_EQ(set.insert(e), reference.insert(e).second);
  }
  set.insertRange(7000, 7100);
  for (std::uint32_t e = 7000; e <= 7100; ++e) reference.insert(e);
  set.insertRange(4990, 7000);  // bridges the gap
  for (std::uint32_t e = 4990; e <= 7000; ++e) reference.insert(e);
  EXPECT_EQ(set.size(), reference.size());
  for (std::uint32_t e = 0; e < 7200; ++e) EXPECT_EQ(set.contains(e), reference.count(e) > 0);
  std::uint64_t previous_last = 0;
  bool first = true;
  for (const auto& [low, high] : set.ranges()) {
    EXPECT_LE(low, high);
    if (!first) {
      EXPECT_GT(low, previous_last + 1);  // disjoint, not adjacent
    }
    previous_last = high;
    first = false;
  }
  for (std::uint32_t e = 0; e <= 7100; ++e) (void)set.insert(e);  // the gaps filled: one range
  EXPECT_EQ(set.ranges().size(), 1u);
  EXPECT_EQ(set.size(), 7101u);
  EXPECT_EQ(EpisodeSet({1, 2, 3, 5}), EpisodeSet({5, 3, 2, 1}));
  EXPECT_TRUE(EpisodeSet({1, 2}).contains(2));
  EXPECT_FALSE(EpisodeSet({1, 2}).contains(0));
  EXPECT_FALSE(EpisodeSet({1, 2}).contains(3));
}

}  // namespace
}  // namespace sensornet::emulator
