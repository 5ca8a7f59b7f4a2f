// The run's record and its one codec (run_record.hpp): a report written by hand as
// docs/reference/report.md describes it decodes into the typed members it says, encodes back to
// the same document (keys this version does not model included), and a report that is wrong
// somewhere is refused naming the key and what was expected there.
#include "sensornet/report/run_record.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>

namespace sensornet::report {
namespace {

using nlohmann::json;

// A degraded two-episode run of two sensors: one survived death (the launcher's fault, with the
// version its failure policy published), one cut-short episode caused by it, a rejection.
json handWrittenReport() {
  return json::parse(R"({
    "schema_version": 1,
    "run_id": "r-1",
    "status": "degraded",
    "faults": [
      {"kind": "process_killed", "process": "sensor_agent-1", "sensor": 1, "sensors": [1],
       "episode": 1, "emulated_time_s": 0.5, "detail": "killed by signal 9", "survived": true,
       "schedule_version": 2},
      {"kind": "cut_short", "process": "fusion_center", "sensor": null, "episode": 1,
       "episodes": [1], "emulated_time_s": null, "detail": "episode 1 was open",
       "ended_by": "interrupted", "caused_by": {"kind": "process_killed", "process": "sensor_agent-1"}}
    ],
    "scenario": {"digest": "abc", "sensors": 2, "states": 4},
    "episodes": 2,
    "episodes_planned": 2,
    "schedule_versions": [
      {"version": 1, "effective_episode": 0, "effective_time_s": 0.0, "surrogate": "info",
       "bracket": {"info": 1.5, "cov": 2.5}, "command_id": 0, "horizon_s": 2.0,
       "rates": [[1.0, 2.0], [3.0, 0.5]]}
    ],
    "summary": {"episodes": 2, "episodes_complete": 1, "episodes_incomplete": 1, "mean": 2.0,
      "std": null, "ci95": null, "ci95_low": null, "ci95_high": null, "realtime_mean": 2.25,
      "received_realtime_mean": 2.25, "bracket": {"info": 1.5, "cov": 2.5}, "meets_bracket": null,
      "delivered_bracket": {"info": 1.75, "cov": 3.0}, "meets_delivered_bracket": null,
      "nees_mean": 3.5, "nees_band_low": 0.09, "nees_band_high": 18.47, "nees_confidence": 0.999,
      "nees_consistent": true, "sent": 30, "received": 27, "expected": 31.5, "lost": 2,
      "dropped_by_network": 1, "late": 0, "refused": 0, "rejected": 3,
      "rejected_by_reason": {"duplicate": 1, "other_run": 2}},
    "sensors": [
      {"sensor_id": 0, "sent": 20, "received": 19, "lost": 1, "dropped_by_network": 0, "late": 0,
       "expected": 21.0, "wrong_version": 0, "refused": 0},
      {"sensor_id": 1, "sent": 10, "received": 8, "lost": 1, "dropped_by_network": 1, "late": 0,
       "expected": 10.5, "wrong_version": 0, "refused": 0}
    ],
    "latency_s": {"median": 0.0001, "p99": 0.002, "quantile_relative_error": 0.000576,
                  "histogram": {"edges_s": [0.0001, 0.001], "counts": [27]}},
    "network_delay_s": {"mean": 0.0, "max": 0.0},
    "arrivals": {"mode": "poisson", "bracket_note": "poisson: ..."},
    "external": {"sensors": [1]},
    "seed": 7,
    "written_at": "2026-12-05T12:00:00Z",
    "stalls": [],
    "covariance_traces": {"times_s": [0.0]},
    "a_key_of_a_later_version": {"x": 1},
    "per_episode": [
      {"episode": 0, "realized_cost": 2.0, "realtime_cost": 2.25, "received_realtime_cost": 2.25,
       "bracket": {"info": 1.5, "cov": 2.5}, "delivered_bracket": {"info": 1.75, "cov": 3.0},
       "schedule_versions": [1], "switch_time_s": 0.0, "nees": 3.5, "complete": true,
       "incomplete_reason": null, "failed_sensors": [], "sent": [10, 5], "received": [10, 5],
       "lost": [0, 0], "dropped_by_network": [0, 0], "late": [0, 0], "expected": [10.5, 5.25],
       "wrong_version": [0, 0], "rejected": {"duplicate": 1}, "drain_s": 0.001, "backlog": 3,
       "latency_median_s": 0.0001, "latency_p99_s": 0.002, "network_delay_mean_s": 0.0,
       "network_delay_max_s": 0.0},
      {"episode": 1, "realized_cost": null, "realtime_cost": null, "received_realtime_cost": null,
       "bracket": {"info": null, "cov": null}, "delivered_bracket": {"info": null, "cov": null},
       "schedule_versions": [1, 2], "switch_time_s": 0.5, "nees": null, "complete": false,
       "incomplete_reason": "sensor 1 failed at 0.5 s", "failed_sensors": [1], "sent": [10, 5],
       "received": [9, 3], "lost": [1, 1], "dropped_by_network": [0, 1], "late": [0, 0],
       "expected": [10.5, 5.25], "wrong_version": [0, 0], "rejected": {}, "drain_s": 0.0,
       "backlog": 0, "latency_median_s": 0.0001, "latency_p99_s": 0.002,
       "network_delay_mean_s": 0.0, "network_delay_max_s": 0.0}
    ]
  })");
}

TEST(RunRecord, DecodesEveryPartOfAReportIntoItsTypedMember) {
  const RunRecord run = decodeRunRecord(handWrittenReport());
  EXPECT_EQ(run.schema_version, 1);
  EXPECT_EQ(run.run_id, "r-1");
  EXPECT_EQ(run.status, RunStatus::Degraded);
  ASSERT_EQ(run.faults.size(), 2U);
  EXPECT_EQ(run.faults[0].kind, FaultKind::ProcessKilled);
  EXPECT_EQ(run.faults[0].namedSensors(), std::vector<int>{1});
  EXPECT_EQ(run.faults[0].survived, true);
  EXPECT_EQ(run.faults[0].schedule_version, 2U);
  EXPECT_FALSE(run.faults[0].isConsequence());
  EXPECT_EQ(run.faults[1].kind, FaultKind::CutShort);
  ASSERT_TRUE(run.faults[1].caused_by.has_value());
  EXPECT_EQ(run.faults[1].caused_by->kind, FaultKind::ProcessKilled);
  EXPECT_EQ(run.faults[1].caused_by->process, "sensor_agent-1");
  EXPECT_EQ(run.faults[1].ended_by, FaultKind::Interrupted);
  EXPECT_EQ(run.faults[1].episodes, std::vector<std::uint32_t>{1});
  EXPECT_FALSE(run.faults[1].sensor.has_value());
  EXPECT_EQ(run.causeCount(), 1U);
  EXPECT_EQ(run.finishedEpisodes(), 2U);
  EXPECT_EQ(run.episodes_planned, 2U);
  ASSERT_EQ(run.schedule_versions.size(), 1U);
  EXPECT_EQ(run.schedule_versions[0].rates[1][0], 3.0);  // interval 1, sensor 0
  EXPECT_EQ(run.summary.episodes_incomplete, 1U);
  EXPECT_EQ(run.summary.mean, 2.0);
  EXPECT_FALSE(run.summary.ci95.has_value());
  EXPECT_FALSE(run.summary.meets_bracket.has_value());
  EXPECT_EQ(run.summary.delivered_bracket->cov, 3.0);
  EXPECT_EQ(run.summary.rejected_by_reason.at(RejectionReason::OtherRun), 2U);
  EXPECT_EQ(run.summary.rejected_by_reason.at(RejectionReason::Duplicate), 1U);
  ASSERT_EQ(run.sensors.size(), 2U);
  EXPECT_EQ(run.sensors[1].dropped_by_network, 1U);
  EXPECT_EQ(run.latency_s->median, 0.0001);
  EXPECT_EQ(run.arrivals->mode, "poisson");
  EXPECT_EQ(run.external->sensors, std::vector<int>{1});
  EXPECT_FALSE(run.external->fusion_center);
  EXPECT_EQ(run.seed, 7U);
  ASSERT_TRUE(run.per_episode.has_value());
  ASSERT_EQ(run.per_episode->size(), 2U);
  const EpisodeRecord& second = (*run.per_episode)[1];
  EXPECT_EQ(second.episode, 1U);
  EXPECT_FALSE(second.realized_cost.has_value());
  EXPECT_FALSE(second.bracket.info.has_value());
  EXPECT_EQ(second.incomplete_reason, "sensor 1 failed at 0.5 s");
  EXPECT_EQ(second.received, (std::vector<std::uint64_t>{9, 3}));
  EXPECT_EQ(second.schedule_versions, (std::vector<std::uint32_t>{1, 2}));
  EXPECT_EQ((*run.per_episode)[0].rejected.at(RejectionReason::Duplicate), 1U);
  EXPECT_TRUE(run.other.contains("a_key_of_a_later_version"));
  EXPECT_TRUE(run.other.contains("covariance_traces"));
}

TEST(RunRecord, EncodesBackTheDocumentItDecoded) {
  const json doc = handWrittenReport();
  EXPECT_EQ(encode(decodeRunRecord(doc)), doc);
  EXPECT_EQ(encode(decodeRunRecord(doc)).dump(), doc.dump());  // numbers as written, too
}

TEST(RunRecord, AReportOfAnEarlierVersionReadsAndStaysWithoutASchemaVersion) {
  json doc = handWrittenReport();
  doc.erase("schema_version");
  doc.erase("per_episode");  // read without its entries
  const RunRecord run = decodeRunRecord(doc);
  EXPECT_FALSE(run.schema_version.has_value());
  EXPECT_FALSE(run.per_episode.has_value());
  EXPECT_EQ(encode(run), doc);
}

// Each wrong document names the key and what it expected.
TEST(RunRecord, AWrongReportIsRefusedNamingTheKeyAndWhatWasExpected) {
  const auto refusal = [](const std::function<void(json&)>& spoil) {
    json doc = handWrittenReport();
    spoil(doc);
    try {
      (void)decodeRunRecord(doc);
    } catch (const RecordError& e) {
      return e.field() + " | " + e.expected();
    }
    return std::string("accepted");
  };
  EXPECT_EQ(refusal([](json& d) { d["status"] = "finished"; }),
            "status | completed, degraded, failed or interrupted");
  EXPECT_EQ(refusal([](json& d) { d["faults"][1]["kind"] = "gremlins"; }).substr(0, 17),
            "faults[1].kind | ");
  EXPECT_EQ(refusal([](json& d) { d.erase("run_id"); }), "run_id | a string");
  EXPECT_EQ(refusal([](json& d) { d.erase("summary"); }), "summary | an object");
  EXPECT_EQ(refusal([](json& d) { d["summary"]["lost"] = -1; }),
            "summary.lost | a whole number >= 0");
  EXPECT_EQ(refusal([](json& d) { d["per_episode"][0]["received"][1] = "3"; }),
            "per_episode[0].received[1] | a whole number >= 0");
  EXPECT_EQ(refusal([](json& d) { d["summary"]["rejected_by_reason"]["cosmic_rays"] = 1; })
                .substr(0, 44),
            "summary.rejected_by_reason.cosmic_rays | a r");
  EXPECT_EQ(refusal([](json& d) { d["faults"][0]["caused_by"] = {{"kind", "crash"}}; }),
            "faults[0].caused_by.process | a string");
  EXPECT_EQ(refusal([](json& d) { d["summary"]["lost"] = 2.5; }),
            "summary.lost | a whole number >= 0");
  // A count built in code is a signed integer; it is the same count as the parsed one.
  EXPECT_EQ(refusal([](json& d) { d["summary"]["lost"] = std::int64_t{3}; }), "accepted");
  json built = handWrittenReport();
  built["summary"]["lost"] = std::int64_t{3};
  EXPECT_EQ(decodeRunRecord(built).summary.lost, 3U);
}

}  // namespace
}  // namespace sensornet::report

namespace sensornet::report {
namespace {

// The schema in docs/ names the same words as the vocabulary tables the codec reads and writes.
template <class E>
std::vector<std::string> tableWords() {
  std::vector<std::string> words;
  for (const auto& w : Words<E>::kTable) words.emplace_back(w.text);
  return words;
}

TEST(RunRecordSchema, NamesEveryWordOfTheVocabulariesTheCodecUses) {
  std::ifstream in(std::string(SENSORNET_SOURCE_DIR) + "/docs/report.schema.json");
  ASSERT_TRUE(in) << "docs/report.schema.json";
  const json schema = json::parse(in);
  EXPECT_EQ(schema.at("$defs").at("fault_kind").at("enum").get<std::vector<std::string>>(),
            tableWords<FaultKind>());
  EXPECT_EQ(schema.at("$defs").at("rejection_reason").at("enum").get<std::vector<std::string>>(),
            tableWords<RejectionReason>());
  EXPECT_EQ(schema.at("properties").at("status").at("enum").get<std::vector<std::string>>(),
            tableWords<RunStatus>());
  EXPECT_EQ(schema.at("properties").at("schema_version").at("const").get<int>(),
            kRecordSchemaVersion);
}

}  // namespace
}  // namespace sensornet::report
