// What the report page reads: the latency histogram and the schedules' rates in the report, the
// covariance traces (against independent computations), and the page and CSV tables made from a
// report (counts against the report's own).

#include "sensornet/emulator/report_page.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "emulator_test_support.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/core/planner.hpp"
#include "sensornet/core/surrogate.hpp"
#include "sensornet/emulator/covariance_trace.hpp"
#include "sensornet/emulator/run_report.hpp"
#include "sensornet/emulator/schedule_book.hpp"
#include "support/csv_rows.hpp"

namespace sensornet::emulator {
namespace {

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
  json faults = json::array({faultEntry(FaultKind::SensorDied, "sensor_agent", 1, 1, 0.5, "killed <9>")});
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

}  // namespace
}  // namespace sensornet::emulator
