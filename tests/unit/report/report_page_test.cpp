// What the report page reads: the latency histogram and the schedules' rates in the report, the
// covariance traces (against independent computations), and the page and CSV tables made from a
// report (counts against the report's own).

#include "sensornet/report/report_page.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "unit/emulator/emulator_test_support.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/planning/planner.hpp"
#include "sensornet/core/surrogate.hpp"
#include "sensornet/emulator/covariance_trace.hpp"
#include "sensornet/emulator/run_report.hpp"
#include "sensornet/emulator/schedule_book.hpp"
#include "sensornet/report/run_record.hpp"
#include "sensornet/report/svg_plot.hpp"
#include "support/csv_rows.hpp"
#include "support/occurrences.hpp"

namespace sensornet::report {
namespace {

using namespace sensornet::emulator;  // the reports the page is drawn from

using nlohmann::json;

TEST(LatencyHistogram, PutsEveryLatencyInTheLogSpacedBinThatHoldsIt) {
  const std::vector<double> latencies = {1.5e-4, 2e-4, 2.1e-4, 9e-4, 1.2e-3, 0.0, 3e-3};
  const json h = latencyHistogram(latencies);
  const std::vector<double> edges = h.at("edges_s").get<std::vector<double>>();
  const std::vector<std::uint64_t> counts = h.at("counts").get<std::vector<std::uint64_t>>();
  ASSERT_EQ(edges.size(), counts.size() + 1);
  // 0 is below the floor (1e-7): the bins start at the decade of the floor, 1e-7.
  EXPECT_NEAR(edges.front(), 1e-7, 1e-19);
  EXPECT_NEAR(edges.back(), 1e-2, 1e-14);
  for (std::size_t i = 1; i < edges.size(); ++i) {
    EXPECT_NEAR(edges[i] / edges[i - 1], std::pow(10.0, 1.0 / kLatencyBinsPerDecade), 1e-12);
  }
  // Brute force: the bin whose edges hold each value (the ones below the floor in the first).
  std::vector<std::uint64_t> expected(counts.size(), 0);
  for (const double v : latencies) {
    std::size_t bin = 0;
    while (bin + 1 < counts.size() && v >= edges[bin + 1]) ++bin;
    ++expected[bin];
  }
  EXPECT_EQ(counts, expected);
  EXPECT_TRUE(latencyHistogram({}).is_null());
}

TEST(ScheduleVersionsJson, CarriesEachVersionsRates) {
  const Scenario scenario = test::smallScenario();
  Eigen::MatrixXd rates(6, 4);
  for (int k = 0; k < 6; ++k) {
    for (int j = 0; j < 4; ++j) rates(k, j) = 0.5 * k + j;
  }
  ScheduleBook book;
  book.add(test::versionOf(0, RateSchedule(scenario.horizon_s, rates)));
  const json versions = scheduleVersionsJson(book);
  ASSERT_EQ(versions.size(), 1u);
  EXPECT_DOUBLE_EQ(versions[0].at("horizon_s").get<double>(), scenario.horizon_s);
  ASSERT_EQ(versions[0].at("rates").size(), 6u);
  EXPECT_DOUBLE_EQ(versions[0].at("rates")[5][3].get<double>(), 5.5);
}

TEST(CovarianceTrace, WithoutMeasurementsBothSurrogatesAreTheOpenLoopCovariance) {
  const Scenario scenario = test::smallScenario();
  const TraceWeight weight = traceWeight(scenario);
  EXPECT_EQ(weight.name, "W_T");  // the random scenario's running weight is zero
  const RateSchedule silent(scenario.horizon_s, Eigen::MatrixXd::Zero(scenario.intervals, 4));
  const TraceCurve fused = fusedCovarianceTrace(scenario, {}, weight, 7);
  const SurrogateTraces s = surrogateTraces(scenario, silent, weight, 7);
  ASSERT_EQ(fused.values.size(), 7u);
  EXPECT_NEAR(fused.values.front(), scenario.plant.P0.trace(), 1e-12);  // W_T = I
  for (std::size_t i = 0; i < 7; ++i) {
    EXPECT_NEAR(s.info.values[i], fused.values[i], 1e-8 * fused.values[i]) << i;
    EXPECT_NEAR(s.cov.values[i], fused.values[i], 1e-8 * fused.values[i]) << i;
  }
}

TEST(CovarianceTrace, TheSurrogateCurvesEndAtTheBracketsTerminalCosts) {
  // W = 0: the bracket's costs are <W_T, P(T)> of the two surrogates (computeBracket, one rollout
  // over [0, T]; the traces chain rollouts over the grid).
  const Scenario scenario = test::smallScenario();
  const RateSchedule uniform(scenario.horizon_s, Eigen::MatrixXd::Constant(scenario.intervals, 4, 2.0));
  const SurrogateTraces s = surrogateTraces(scenario, uniform, traceWeight(scenario), 50);
  const CostBracket bracket = computeBracket(scenario, uniform);
  EXPECT_NEAR(s.info.values.back(), bracket.info, 1e-7 * bracket.info);
  EXPECT_NEAR(s.cov.values.back(), bracket.cov, 1e-7 * bracket.cov);
  for (std::size_t i = 0; i < s.info.values.size(); ++i) {
    EXPECT_LE(s.info.values[i], s.cov.values[i] * (1 + 1e-9)) << i;  // P_info <= Ps
  }
}

TEST(CovarianceTrace, TheFilterCurveDropsAtAMeasurementAndMatchesTheFilterAtT) {
  const Scenario scenario = test::smallScenario();
  std::vector<FusedMeasurement> measurements(2);
  measurements[0].sensor = 1;
  measurements[0].time_s = 1.5;  // on the grid (T = 3, 7 points: every 0.5 s)
  measurements[1].sensor = 2;
  measurements[1].seq = 0;
  measurements[1].time_s = 0.75;
  const TraceWeight weight = traceWeight(scenario);
  const TraceCurve with = fusedCovarianceTrace(scenario, measurements, weight, 7);
  const TraceCurve without = fusedCovarianceTrace(scenario, {}, weight, 7);
  EXPECT_NEAR(with.values[1], without.values[1], 1e-12);  // before the first measurement
  EXPECT_LT(with.values[2], without.values[2]);
  // Independent: the filter run by hand, in timestamp order, to T.
  CdKalmanFilter filter(scenario);
  filter.reset();
  filter.propagateTo(0.75);
  filter.updateCovariance(2);
  filter.propagateTo(1.5);
  filter.updateCovariance(1);
  EXPECT_NEAR(with.values[3], filter.covariance().trace(), 1e-9 * with.values[3]);
  filter.propagateTo(scenario.horizon_s);
  EXPECT_NEAR(with.values.back(), filter.terminalCost(), 1e-9 * with.values.back());
}

// A report of 3 episodes and 2 sensors, one incomplete, with a fault.
json sampleReport() {
  RunReport report("run-x", "digest-1", 2, 3);
  for (std::uint32_t i = 0; i < 3; ++i) {
    EpisodeResult e;
    e.episode = i;
    e.realized_cost = 2.0 + i;
    e.realtime_cost = 2.5 + i;
    e.bracket = {1.0, 6.0};
    e.delivered_bracket = {1.5, 6.5};
    e.versions = {0};
    e.complete = i != 1;
    e.sensors.resize(2);
    e.sensors[0] = {10 + i, 9, 1, 0, 0, 0, 10.5, 0, 0, true};
    e.sensors[1] = {7, 5, 0, 2, 0, 0, 7.25, 1, 0, true};
    e.latencies_s = {1e-4 * (i + 1), 2e-3};
    report.addLatencies(e.latencies_s);
    report.add(episodeEntry(e));
  }
  json faults = json::array({{{"kind", "sensor_died"},
                              {"process", "sensor_agent"},
                              {"sensor", 1},
                              {"episode", 1u},
                              {"emulated_time_s", 0.5},
                              {"detail", "killed <9>"}}});
  return report.toJson("degraded", faults, json::array());
}

using sensornet::testing::csvRows;

TEST(ReportTables, HaveOneRowPerEpisodeAndPerSensorWithTheReportsCounts) {
  const json report = sampleReport();
  const ReportTables tables = reportTables(report, "r.json");
  const auto episodes = csvRows(tables.episodes);
  ASSERT_EQ(episodes.size(), 4u);
  ASSERT_EQ(episodes[0].size(), 19u);
  EXPECT_EQ(episodes[0][0], "episode");
  for (std::size_t i = 1; i < episodes.size(); ++i) {
    ASSERT_EQ(episodes[i].size(), 19u) << tables.episodes;
    const json& e = report.at("per_episode")[i - 1];
    EXPECT_EQ(std::stod(episodes[i][0]), e.at("episode").get<double>());
    EXPECT_EQ(episodes[i][1], e.at("complete").get<bool>() ? "1" : "0");
    EXPECT_EQ(std::stod(episodes[i][2]), e.at("realized_cost").get<double>());
    EXPECT_EQ(std::stod(episodes[i][11]), e.at("sent")[0].get<double>() + e.at("sent")[1].get<double>());
    EXPECT_EQ(std::stod(episodes[i][14]), 2.0);  // dropped_by_network: sensor 1's 2
  }
  const auto sensors = csvRows(tables.sensors);
  ASSERT_EQ(sensors.size(), 3u);
  EXPECT_EQ(sensors[0], (std::vector<std::string>{"sensor_id", "sent", "received", "lost",
                                                  "dropped_by_network", "late", "expected",
                                                  "wrong_version"}));
  for (std::size_t j = 0; j < 2; ++j) {
    const json& s = report.at("sensors")[j];
    for (std::size_t c = 0; c < sensors[0].size(); ++c) {
      EXPECT_EQ(std::stod(sensors[j + 1][c]), s.at(sensors[0][c]).get<double>()) << sensors[0][c];
    }
  }
}

TEST(ReportPage, HasATitleAndOnePlotPerPartWithMarksAndNoFetchedResource) {
  const std::string page = reportPage(sampleReport(), "r.json");
  EXPECT_NE(page.find("<title>sensornet run run-x</title>"), std::string::npos);
  EXPECT_NE(page.find("scenario digest-1"), std::string::npos);
  const std::vector<std::pair<std::string, std::string>> plots = {
      {"plot-cost", "<circle"}, {"plot-cost", "<rect"}, {"plot-sensors", "<rect"},
      {"plot-latency", "<rect"}, {"plot-faults", "<circle"}};
  for (const auto& [id, mark] : plots) {
    const std::size_t at = page.find("id=\"" + id + "\"");
    ASSERT_NE(at, std::string::npos) << id;
    const std::size_t marks = page.find("<g class=\"marks\"", at);
    const std::size_t end = page.find("</g>", marks);
    EXPECT_NE(page.substr(marks, end - marks).find(mark), std::string::npos) << id << " " << mark;
  }
  // No schedule rates nor traces in this report: said, not drawn.
  EXPECT_NE(page.find("carries no schedule rates"), std::string::npos);
  EXPECT_NE(page.find("carries no covariance traces"), std::string::npos);
  EXPECT_NE(page.find("killed &lt;9&gt;"), std::string::npos);
  EXPECT_EQ(page.find("src="), std::string::npos);
  EXPECT_EQ(page.find("href="), std::string::npos);
  EXPECT_EQ(page.find("@import"), std::string::npos);
  EXPECT_NE(page.find("@media print"), std::string::npos);
}

// Issue 49: latency figures withheld because clocks disagree are said to be not known, with
// why, not drawn from a histogram whose floor holds the impossible (negative) latencies; and
// the record's codec keeps the reason.
TEST(ReportPage, SaysWhyLatencyIsNotKnownInsteadOfDrawingIt) {
  json report = sampleReport();
  report["latency_s"]["median"] = nullptr;
  report["latency_s"]["p99"] = nullptr;
  report["latency_s"]["unknown_because"] = "the clocks disagree: sensor 3 stamped <late>";
  EXPECT_EQ(sensornet::report::encode(sensornet::report::decodeRunRecord(report))
                .at("latency_s")
                .at("unknown_because"),
            report["latency_s"]["unknown_because"]);
  const std::string page = reportPage(report, "r.json");
  EXPECT_NE(page.find("Not known: the clocks disagree: sensor 3 stamped &lt;late&gt;."), std::string::npos);
  EXPECT_EQ(page.find("id=\"plot-latency\""), std::string::npos);
}

// The report's clocks read back through the record as written, and the page lists each process
// with its signed offset and uncertainty, marking only the one surely beyond the bound; a fault
// naming several sensors lists them in the faults table (not "–").
TEST(ReportPage, ListsEachProcesssClockAndTheSensorsAFaultNames) {
  json report = sampleReport();
  report["clocks"] = {{"bound_s", 1e-3},
                      {"echoes_refused", 0},
                      {"processes",
                       {{{"process", "sensor_agent 10@edge-2"}, {"sensors", {3, 4}},
                         {"offset_s", -2.0}, {"uncertainty_s", 2e-4}, {"exchanges", 12}},
                        {{"process", "sensor_agent 11@edge-1"}, {"sensors", {0}},
                         {"offset_s", 5e-4}, {"uncertainty_s", 6e-4}, {"exchanges", 12}}}}};
  report["faults"].push_back({{"kind", "clock_offset"}, {"process", "sensor_agent"},
                              {"sensors", {3, 4}}, {"detail", "behind"}});
  EXPECT_EQ(sensornet::report::encode(sensornet::report::decodeRunRecord(report)).at("clocks"),
            report["clocks"]);
  const std::string page = reportPage(report, "r.json");
  const std::size_t table = page.find("<table class=\"clocks\">");
  ASSERT_NE(table, std::string::npos);
  const std::string clocks = page.substr(table, page.find("</table>", table) - table);
  EXPECT_NE(clocks.find("<td>3, 4</td><td>−2 s</td><td>200 µs</td><td>12</td><td>beyond the bound</td>"),
            std::string::npos)
      << clocks;
  EXPECT_NE(clocks.find("<td>0</td><td>+500 µs</td><td>600 µs</td><td>12</td><td></td>"), std::string::npos)
      << clocks;
  EXPECT_NE(page.find("<td>clock_offset</td><td>sensor_agent</td><td>3, 4</td>"), std::string::npos);
}

TEST(ReportPage, RefusesAReportWithoutWhatItReadsNamingTheField) {
  json report = sampleReport();
  report.erase("run_id");
  try {
    (void)reportPage(report, "bad.json");
    FAIL() << "accepted a report without run_id";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "bad.json: run_id: expected a string (the run id)");
  }
  report = sampleReport();
  report["per_episode"][1].erase("episode");
  EXPECT_THROW((void)reportTables(report, "bad.json"), InputError);
  EXPECT_THROW((void)reportPage(json::array(), "bad.json"), InputError);
}

// The page reads the record the one codec decodes: what does not decode is one line naming the
// report, the field and what was expected there.
TEST(ReportPage, NamesTheFieldThatDoesNotDecode) {
  const auto messageOf = [](const json& report) {
    try {
      (void)reportPage(report, "bad.json");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  json report = sampleReport();
  report.erase("status");
  EXPECT_EQ(messageOf(report), "bad.json: status: expected the run's status: completed, "
                               "degraded, failed or interrupted");
  report = sampleReport();
  report["per_episode"][1].erase("complete");
  EXPECT_EQ(messageOf(report), "bad.json: per_episode[1].complete: expected true or false");
  report = sampleReport();
  report["faults"][0]["kind"] = "sensor_fainted";
  const std::string kind = messageOf(report);
  EXPECT_EQ(kind.rfind("bad.json: faults[0].kind: expected ", 0), 0u) << kind;
  EXPECT_EQ(kind.find('\n'), std::string::npos) << kind;
  report = sampleReport();
  report["sensors"][0]["sent"] = -1;
  EXPECT_EQ(messageOf(report), "bad.json: sensors[0].sent: expected a whole number >= 0");
}

TEST(ReportPage, TheRecordGivesThePageAndTablesOfItsDocument) {
  const json report = sampleReport();
  RunRecord run = decodeRunRecord(report);
  EXPECT_EQ(reportPage(run, "r.json"), reportPage(report, "r.json"));
  const ReportTables from_record = reportTables(run, "r.json");
  const ReportTables from_document = reportTables(report, "r.json");
  EXPECT_EQ(from_record.episodes, from_document.episodes);
  EXPECT_EQ(from_record.sensors, from_document.sensors);
  // Read without its episode entries (EpisodeEntries::Skipped), a record has none to draw:
  // that is said, not drawn as a run that fused no episode.
  run.per_episode.reset();
  try {
    (void)reportPage(run, "r.json");
    FAIL() << "drew a record without its episode entries";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "per_episode");
  }
  EXPECT_THROW((void)reportTables(run, "r.json"), InputError);
}

// A report with `versions` schedule versions switching mid-episode, one after the other in
// consecutive episodes (v2 in episode 1 at t = 1.5 s, v3 in episode 2 ...), as live re-plans make
// them; sensor j's rate in version v is v + j in every interval.
json reportWithVersions(unsigned versions, unsigned episodes) {
  json report = sampleReport();
  // Numbers and counts unsigned, as a report read from its file has them (the record's types).
  json list = json::array();
  for (unsigned v = 1; v <= versions; ++v) {
    json rates = json::array();
    for (int k = 0; k < 3; ++k) rates.push_back({v + 0.0, v + 1.0});
    list.push_back({{"version", v},
                    {"effective_episode", v == 1 ? 0u : v - 1},
                    {"effective_time_s", v == 1 ? 0.0 : 1.5},
                    {"surrogate", "cov"},
                    {"bracket", {{"info", 1.0}, {"cov", 2.0}}},
                    {"horizon_s", 3.0},
                    {"rates", rates}});
  }
  report["schedule_versions"] = list;
  json per_episode = json::array();
  for (unsigned e = 0; e < episodes; ++e) {
    json entry = report.at("per_episode").at(0);
    entry["episode"] = e;
    per_episode.push_back(entry);
  }
  report["per_episode"] = per_episode;
  return report;
}

// The <svg> element of `id` in a page.
std::string svgOf(const std::string& page, const std::string& id) {
  const std::size_t at = page.find("id=\"" + id + "\"");
  if (at == std::string::npos) return {};
  const std::size_t from = page.rfind("<svg", at);
  return page.substr(from, page.find("</svg>", at) - from);
}

using sensornet::testing::occurrences;

TEST(ReportPage, DrawsOneScheduleMapWithEverySwitchMarked) {
  const std::string page = reportPage(reportWithVersions(10, 12), "r.json");
  EXPECT_EQ(occurrences(page, "<svg xmlns"), 5u) << "cost, one schedule map, sensors, latency, faults";
  EXPECT_EQ(occurrences(page, "id=\"plot-schedule\""), 1u) << "one map, not one per version";
  const std::string map = svgOf(page, "plot-schedule");
  for (int v = 2; v <= 10; ++v) {
    EXPECT_NE(map.find(">v" + std::to_string(v) + "</text>"), std::string::npos) << v;
  }
  // Episode 1 switches at t = 1.5 s, the middle of interval 1 (of 3): sensor 0 runs 1 Hz before
  // and 2 Hz after; the cells say so.
  EXPECT_NE(map.find("sensor 0, episode 1, t in [1, 1.5) s: 1 Hz (v1)"), std::string::npos);
  EXPECT_NE(map.find("sensor 0, episode 1, t in [1.5, 2) s: 2 Hz (v2)"), std::string::npos);
  EXPECT_NE(map.find("sensor 1, episode 11, t in [2, 3) s: 11 Hz (v10)"), std::string::npos);
}

TEST(ReportPage, AScheduleMapOfManyEpisodesShowsEachBlocksMeanRate) {
  // 2000 episodes x 3 intervals: too many cells, so a column is a block of episodes. Version 2
  // takes effect in episode 1 at 1.5 s: episode 0 runs v1 (1 Hz for sensor 0), episode 1 half
  // and half (1.5 Hz), every later one v2 (2 Hz).
  const std::string page = reportPage(reportWithVersions(2, 2000), "r.json");
  const std::string map = svgOf(page, "plot-schedule");
  EXPECT_NE(page.find("mean rate over a block of episodes"), std::string::npos);
  const std::size_t rects = occurrences(map, "<rect");
  EXPECT_LE(rects, 2u * 600u + 10u);
  // The first block holds episodes 0-3 (2000 episodes in at most 600 columns: 4 a column):
  // sensor 0's mean is (1 + 1.5 + 2 + 2) / 4 = 1.625 Hz.
  EXPECT_NE(map.find("sensor 0, episodes 0-3: mean 1.625 Hz"), std::string::npos) << map.substr(0, 3000);
}

TEST(ReportPage, AnAbortedEpisodesCostDoesNotFlattenTheCostAxis) {
  json report = reportWithVersions(1, 6);
  for (json& e : report["per_episode"]) {
    e["complete"] = true;
    e["realized_cost"] = 20.0 + e.at("episode").get<double>();
  }
  report["per_episode"][5]["complete"] = false;
  report["per_episode"][5]["realized_cost"] = 931.5;
  const std::string cost = svgOf(reportPage(report, "r.json"), "plot-cost");
  // The axis ends near the complete episodes' 25 (the bracket [1, 2] is below), not near 931.5.
  double top_tick = 0.0;
  for (std::size_t at = cost.find("text-anchor=\"end\">"); at != std::string::npos;
       at = cost.find("text-anchor=\"end\">", at + 1)) {
    top_tick = std::max(top_tick, std::stod(cost.substr(at + 18)));
  }
  EXPECT_GE(top_tick, 25.0);
  EXPECT_LT(top_tick, 100.0);
  EXPECT_NE(cost.find("episode 5: 931.5 (incomplete), off the scale"), std::string::npos);
}

TEST(ReportPage, PrintsNoIntervalWithOneCompleteEpisodeAndNoMeanWithNone) {
  json report = sampleReport();
  report["summary"]["episodes_complete"] = 1u;
  report["summary"]["mean"] = 19.59;
  report["summary"]["ci95_low"] = 19.59;
  report["summary"]["ci95_high"] = 19.59;
  std::string page = reportPage(report, "r.json");
  EXPECT_NE(page.find("19.59, no 95% interval (one complete episode)"), std::string::npos);
  EXPECT_EQ(page.find("[19.59, 19.59]"), std::string::npos);
  report["summary"]["episodes_complete"] = 0u;
  report["summary"]["mean"] = 0.0;
  page = reportPage(report, "r.json");
  EXPECT_NE(page.find("<th>mean realized cost</th><td>not measured (no complete episode)"),
            std::string::npos);
}

// Issue 24: beside the planned bracket, what the schedule delivered, and beside the realized
// cost, the real-time one; neither where it is the same number.
TEST(ReportPage, ShowsTheDeliveredBracketAndTheRealtimeCostWhereTheyDiffer) {
  json report = sampleReport();
  std::string page = reportPage(report, "r.json");
  const std::string cost = svgOf(page, "plot-cost");
  double realtime_sum = 0.0;
  int complete = 0;
  for (const json& e : report.at("per_episode")) {
    const std::string k = formatTick(e.at("episode").get<double>());
    EXPECT_NE(cost.find("episode " + k + ": delivered bracket [1.5, 6.5]"), std::string::npos) << k;
    const std::string realtime =
        "episode " + k + ": real-time cost " + formatTick(e.at("realtime_cost").get<double>());
    if (e.at("complete").get<bool>()) {
      EXPECT_NE(cost.find(realtime), std::string::npos) << k;
      realtime_sum += e.at("realtime_cost").get<double>();
      ++complete;
    } else {
      EXPECT_EQ(cost.find(realtime), std::string::npos) << "an incomplete episode " << k;
    }
  }
  EXPECT_NE(cost.find(">bracket delivered<"), std::string::npos);
  EXPECT_NE(page.find("<td>[1.5, 6.5]</td>"), std::string::npos);
  EXPECT_NE(page.find("<th>mean real-time cost (what had arrived by each instant)</th><td>" +
                      formatTick(realtime_sum / complete) + "</td>"),
            std::string::npos);
  const std::string dropped_row = "<th>sent / received / dropped by the emulated network / lost";
  EXPECT_NE(page.find(dropped_row), std::string::npos);

  // Nothing delivered short of the plan, nothing late: only the planned bracket is shown.
  for (json& e : report["per_episode"]) {
    e["delivered_bracket"] = e.at("bracket");
    e["realtime_cost"] = e.at("realized_cost");
  }
  report["summary"]["delivered_bracket"] = report["summary"]["bracket"];
  report["summary"]["realtime_mean"] = report["summary"]["mean"];
  report["summary"]["dropped_by_network"] = 0u;
  page = reportPage(report, "r.json");
  EXPECT_EQ(page.find("delivered"), std::string::npos);
  EXPECT_EQ(page.find("real-time"), std::string::npos);
  EXPECT_EQ(page.find(dropped_row), std::string::npos);
}

TEST(ReportPage, WritesFaultNumbersToSixDigitsNotAsRawFloats) {
  json report = sampleReport();
  report["faults"][0]["emulated_time_s"] = 0.8732357025146484;
  const std::string page = reportPage(report, "r.json");
  EXPECT_EQ(page.find("0.8732357025146484"), std::string::npos);
  EXPECT_NE(page.find("<td>0.873236</td>"), std::string::npos);
}

}  // namespace
}  // namespace sensornet::report
