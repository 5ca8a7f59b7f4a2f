// A Report sample and back (wire/messages.hpp): what the launcher records of an external
// fusion center's Report must be the per_episode entry of the same result, field by field, for
// everything the wire carries; what it does not carry is null or zero, never invented.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <vector>

#include "sensornet/core/input_error.hpp"
#include "sensornet/wire/messages.hpp"
#include "sensornet/emulator/run_report.hpp"

namespace sensornet::wire {
namespace {

using namespace sensornet::emulator;  // the core types the samples carry

using nlohmann::json;

EpisodeResult resultOfThreeSensors() {
  EpisodeResult e;
  e.episode = 7;
  e.realized_cost = 12.375;
  e.realtime_cost = 13.5;
  e.received_realtime_cost = 13.25;
  e.bracket = {10.0, 20.0};
  e.delivered_bracket = {11.0, 21.0};
  e.versions = {2, 3};
  e.switch_time_s = 1.25;
  e.nees = 3.75;
  e.sensors.resize(3);
  for (std::size_t j = 0; j < 3; ++j) {  // different per sensor, so that an order slip shows
    e.sensors[j].sent = 10 + j;
    e.sensors[j].received = 8 + j;
    e.sensors[j].lost = 1;
    e.sensors[j].dropped_by_network = 1;  // sent = received + lost + dropped_by_network
    e.sensors[j].late = j;  // and the rest per sensor, so that an order slip shows
    e.sensors[j].expected = 9.5 + static_cast<double>(j);
    e.sensors[j].tallied = true;
  }
  e.complete = false;
  e.incomplete_reason = "sensor 1 failed at 0.5 s";
  e.failed_sensors = {1};
  e.drain_s = 0.25;
  e.backlog = 4;
  return e;
}

TEST(ReportCodec, TheEntryOfAReportIsTheEntryOfItsResultForEveryFieldTheWireCarries) {
  const EpisodeResult e = resultOfThreeSensors();
  RunSummary summary;
  summary.latency_median_s = 0.002;
  summary.latency_p99_s = 0.009;
  std::vector<sensornet_SensorCounts> counts;
  const sensornet_Report sample = reportSample("run-x", e, summary, counts);
  const json got = episodeEntryOfReport(sample, 3);
  const json want = episodeEntry(e);
  for (const char* key : {"episode", "realized_cost", "realtime_cost", "bracket",
                          "delivered_bracket", "schedule_versions", "nees", "complete",
                          "incomplete_reason", "sent", "received", "lost", "dropped_by_network",
                          "late", "expected"}) {
    EXPECT_EQ(got.at(key), want.at(key)) << key;
  }
  // Not on the wire: null or zero, never a guess.
  EXPECT_TRUE(got.at("received_realtime_cost").is_null());
  EXPECT_EQ(got.at("switch_time_s"), 0.0);
  EXPECT_EQ(got.at("failed_sensors"), json::array());
  EXPECT_EQ(got.at("drain_s"), 0.0);
  EXPECT_EQ(got.at("latency_median_s"), 0.002);
  EXPECT_EQ(got.at("latency_p99_s"), 0.009);
}

TEST(ReportCodec, AReportWhoseCountsDoNotFitTheScenarioIsRefusedNamingTheField) {
  const EpisodeResult e = resultOfThreeSensors();
  std::vector<sensornet_SensorCounts> counts;
  const sensornet_Report sample = reportSample("run-x", e, RunSummary{}, counts);
  try {
    (void)episodeEntryOfReport(sample, 2);  // the scenario has two sensors, the Report three
    FAIL() << "a count of sensor 2 was taken for a scenario of two sensors";
  } catch (const InputError& error) {
    EXPECT_EQ(error.field(), "counts.sensor_id");
  }
  counts[2].sensor_id = 0;  // sensor 0 twice
  EXPECT_THROW((void)episodeEntryOfReport(sample, 3), InputError);
}

// An estimator of a user's may compute no NEES (it keeps no mean): its Reports carry NaN, the
// entries null, and the run's summary averages the NEES over the episodes that have one (null
// when none has); a complete episode without a finite cost is refused, naming the field.
TEST(ReportCodec, AReportWithoutNeesMakesANullNeesAndACompleteOneNeedsAFiniteCost) {
  EpisodeResult e = resultOfThreeSensors();
  e.complete = true;
  e.incomplete_reason.clear();
  e.nees = std::nan("");
  std::vector<sensornet_SensorCounts> counts;
  const sensornet_Report no_nees = reportSample("run-x", e, RunSummary{}, counts);
  const json entry = episodeEntryOfReport(no_nees, 3);
  EXPECT_TRUE(entry.at("nees").is_null());

  RunReport without("run-x", "d", 3, 2);
  without.add(entry);
  without.add(entry);
  EXPECT_TRUE(std::isnan(without.summary().nees_mean));
  EXPECT_EQ(without.summary().mean, e.realized_cost);
  EXPECT_TRUE(without.toJson("completed", json::array(), json::array())
                  .at("summary")
                  .at("nees_mean")
                  .is_null());

  RunReport mixed("run-x", "d", 3, 2);
  mixed.add(entry);
  e.nees = 2.5;
  std::vector<sensornet_SensorCounts> more_counts;
  mixed.add(episodeEntryOfReport(reportSample("run-x", e, RunSummary{}, more_counts), 3));
  EXPECT_EQ(mixed.summary().nees_mean, 2.5) << "the mean of the one NEES there is";

  e.realized_cost = std::nan("");
  std::vector<sensornet_SensorCounts> bad_counts;
  const sensornet_Report no_cost = reportSample("run-x", e, RunSummary{}, bad_counts);
  try {
    (void)episodeEntryOfReport(no_cost, 3);
    FAIL() << "a complete episode without a cost was taken";
  } catch (const InputError& error) {
    EXPECT_EQ(error.field(), "realized_cost");
  }
}

}  // namespace
}  // namespace sensornet::wire
