#pragma once
// The record of a run, typed: what the report file (report.json) holds, with one JSON codec that
// writes and reads it. Every reader takes the record instead of reading keys by string; a key
// this version does not model is kept as written (`other`), so that decoding and encoding a
// report gives back the same document, and the keys of older reports stay readable.
//
//   const RunRecord run = decodeRunRecord(json::parse(text));   // or RecordError
//   if (run.status == RunStatus::Degraded) ...
//   for (const FaultRecord& f : run.faults) if (!f.isConsequence()) ...
//   run.summary.rejected_by_reason[RejectionReason::Duplicate];
//   const nlohmann::json doc = encode(run);                      // the same keys back
//
// docs/report.schema.json is the JSON Schema of the document; docs/reference/report.md says what
// each key means. `schema_version` (kRecordSchemaVersion) is written by every writer of this
// version; a report without it is of an earlier version and reads the same.

#include <cstddef>
#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "sensornet/emulator/vocabulary.hpp"

namespace sensornet::report {

using emulator::FaultKind;
using emulator::RejectionReason;
using emulator::RunStatus;

inline constexpr int kRecordSchemaVersion = 1;

// A report that does not decode: where (a JSON path such as "faults[2].kind") and what was
// expected there.
class RecordError : public std::runtime_error {
 public:
  RecordError(std::string field, std::string expected);
  [[nodiscard]] const std::string& field() const { return field_; }
  [[nodiscard]] const std::string& expected() const { return expected_; }

 private:
  std::string field_;
  std::string expected_;
};

// The two sides of the cost bracket, J(P_info) <= E[J(P)] <= J(P_cov); none where not finite.
struct BracketRecord {
  std::optional<double> info;
  std::optional<double> cov;
};

using RejectionTally = std::map<RejectionReason, std::uint64_t>;

// The fault an entry followed from (fault_causes.hpp).
struct FaultCause {
  FaultKind kind = FaultKind::Interrupted;
  std::string process;
};

struct FaultRecord {
  FaultKind kind = FaultKind::ProcessFailed;
  std::string process;                    // "fusion_center", "sensor_agent-0-2", "network", ...
  std::optional<int> sensor;              // its one sensor
  std::optional<std::vector<int>> sensors;  // the sensors of the process (launcher faults)
  std::optional<std::uint32_t> episode;
  std::optional<std::vector<std::uint32_t>> episodes;  // every episode it touched (cut_short)
  std::optional<double> emulated_time_s;
  std::string detail;
  std::optional<bool> survived;                 // the launcher's: the run went on
  std::optional<std::uint32_t> schedule_version;  // the version the failure policy published
  std::optional<FaultCause> caused_by;          // a consequence of that cause
  std::optional<FaultKind> ended_by;            // cut_short: what ended the run
  nlohmann::json other = nlohmann::json::object();

  [[nodiscard]] bool isConsequence() const { return caused_by.has_value(); }
  // The sensors it names: `sensors`, else its one `sensor`, else none.
  [[nodiscard]] std::vector<int> namedSensors() const;
};

// One finished episode: an entry of per_episode and a line of the episode log. Per-sensor
// counts are indexed by sensor id.
struct EpisodeRecord {
  std::uint32_t episode = 0;
  std::optional<double> realized_cost;  // none: not fused (a restarted fusion center)
  std::optional<double> realtime_cost;
  std::optional<double> received_realtime_cost;
  BracketRecord bracket;
  BracketRecord delivered_bracket;
  std::vector<std::uint32_t> schedule_versions;
  double switch_time_s = 0.0;
  std::optional<double> nees;
  bool complete = false;
  std::optional<std::string> incomplete_reason;
  std::vector<int> failed_sensors;
  std::vector<std::uint64_t> sent, received, lost, dropped_by_network, late, wrong_version;
  std::vector<std::uint64_t> refused;  // sent samples refused as malformed (empty: none read)
  std::vector<double> expected;
  RejectionTally rejected;
  double drain_s = 0.0;
  std::uint64_t backlog = 0;
  std::optional<double> latency_median_s;  // none: nothing measured, or clocks known apart
  std::optional<double> latency_p99_s;
  double network_delay_mean_s = 0.0;
  double network_delay_max_s = 0.0;
  nlohmann::json other = nlohmann::json::object();
};

struct SummaryRecord {
  std::uint64_t episodes = 0;
  std::uint64_t episodes_complete = 0;
  std::uint64_t episodes_incomplete = 0;
  std::optional<double> mean, std_dev, ci95, ci95_low, ci95_high;  // over complete episodes ("std")
  std::optional<double> realtime_mean, received_realtime_mean, nees_mean;
  // The band of nees_mean that holds with probability nees_confidence for a consistent filter
  // (chi-square(n K) / K), and whether nees_mean lies in it; none: no NEES measured.
  std::optional<double> nees_band_low, nees_band_high, nees_confidence;
  std::optional<bool> nees_consistent;
  std::optional<BracketRecord> bracket;
  std::optional<bool> meets_bracket;  // none: undetermined (fewer than two complete episodes)
  std::optional<BracketRecord> delivered_bracket;
  std::optional<bool> meets_delivered_bracket;
  std::uint64_t sent = 0, received = 0, lost = 0, dropped_by_network = 0, late = 0;
  std::uint64_t refused = 0;  // sent samples refused as malformed (also among rejected)
  double expected = 0.0;
  std::uint64_t rejected = 0;  // the total of rejected_by_reason
  RejectionTally rejected_by_reason;
  nlohmann::json other = nlohmann::json::object();
};

struct SensorRecord {
  int sensor_id = 0;
  std::uint64_t sent = 0, received = 0, lost = 0, dropped_by_network = 0, late = 0,
                wrong_version = 0, refused = 0;
  double expected = 0.0;
};

struct ScheduleVersionRecord {
  std::uint32_t version = 0;
  std::uint32_t effective_episode = 0;
  double effective_time_s = 0.0;
  std::string surrogate;  // how it was made: uniform, info, cov, mc, file
  BracketRecord bracket;
  std::uint64_t command_id = 0;  // the re-plan command that made it (0: none)
  double horizon_s = 0.0;
  std::vector<std::vector<double>> rates;  // N intervals of M rates (Hz)
  nlohmann::json other = nlohmann::json::object();
};

struct ScenarioRecord {
  std::string digest;
  int sensors = 0;
  int states = 0;
};

struct LatencyRecord {
  std::optional<double> median;  // publish to fusion, seconds; none: nothing measured
  std::optional<double> p99;
  std::optional<double> quantile_relative_error;
  // Set when the figures cannot be believed (clocks that disagree): median and p99 are then null.
  std::optional<std::string> unknown_because;
  nlohmann::json histogram;  // {"edges_s": [...], "counts": [...]} or null
};

// One sensor process's wall clock against the fusion center's, measured both ways
// (docs/wire-protocol.md, "Clocks"): the true offset lies within uncertainty_s of offset_s.
struct ClockProcessRecord {
  std::string process;
  std::vector<int> sensors;
  double offset_s = 0.0;  // its clock minus the fusion center's: > 0 ahead
  double uncertainty_s = 0.0;
  std::optional<double> farthest_offset_s;  // the estimate farthest from zero for certain
  std::optional<double> farthest_uncertainty_s;
  std::uint64_t exchanges = 0;
};

struct ClocksRecord {
  double bound_s = 0.0;  // farther than this for certain: a clock_offset fault
  std::vector<ClockProcessRecord> processes;
  std::uint64_t echoes_refused = 0;
};

struct NetworkDelayRecord {
  std::optional<double> mean;  // emulated seconds; none: nothing received
  std::optional<double> max;
};

struct ArrivalsRecord {
  std::string mode;  // poisson or timetable
  std::string bracket_note;
};

// The roles a participant of the user's played.
struct ExternalRoles {
  std::vector<int> sensors;
  bool fusion_center = false;
};

struct RunRecord {
  std::optional<int> schema_version;  // none: written before the record had one
  std::string run_id;
  RunStatus status = RunStatus::Failed;
  std::vector<FaultRecord> faults;
  std::optional<ScenarioRecord> scenario;
  std::optional<std::uint64_t> episodes;  // finished
  std::optional<std::uint64_t> episodes_planned;
  std::vector<ScheduleVersionRecord> schedule_versions;
  SummaryRecord summary;
  std::vector<SensorRecord> sensors;
  std::optional<LatencyRecord> latency_s;
  std::optional<NetworkDelayRecord> network_delay_s;
  std::optional<ClocksRecord> clocks;  // none: written before clocks were measured
  std::optional<ArrivalsRecord> arrivals;
  std::optional<ExternalRoles> external;
  std::optional<std::uint64_t> seed;
  std::optional<std::string> written_at;
  std::optional<std::string> rebuilt_from;  // the launcher rebuilt it from the episode log
  std::optional<std::string> built_from;    // an external fusion center's Reports
  // Absent when the document was read without them (EpisodeEntries::Skipped).
  std::optional<std::vector<EpisodeRecord>> per_episode;
  // Kept as written: stalls, covariance_traces, requirements, reference_fusion, and any key of
  // a later version.
  nlohmann::json other = nlohmann::json::object();

  // Faults that are not another's consequence (what every count of faults counts).
  [[nodiscard]] std::size_t causeCount() const;
  // The finished episodes: `episodes`, else as many as per_episode lists.
  [[nodiscard]] std::uint64_t finishedEpisodes() const;
};

// Decoding throws RecordError naming the first key that is missing or of the wrong type.
[[nodiscard]] RunRecord decodeRunRecord(const nlohmann::json& doc);
[[nodiscard]] EpisodeRecord decodeEpisode(const nlohmann::json& entry);
[[nodiscard]] FaultRecord decodeFault(const nlohmann::json& entry);
[[nodiscard]] SummaryRecord decodeSummary(const nlohmann::json& summary);

[[nodiscard]] nlohmann::json encode(const RunRecord& run);
[[nodiscard]] nlohmann::json encode(const EpisodeRecord& episode);
[[nodiscard]] nlohmann::json encode(const FaultRecord& fault);
[[nodiscard]] nlohmann::json encode(const std::vector<FaultRecord>& faults);
[[nodiscard]] nlohmann::json encode(const SummaryRecord& summary);
[[nodiscard]] nlohmann::json encode(const BracketRecord& bracket);
[[nodiscard]] nlohmann::json encode(const RejectionTally& tally);
[[nodiscard]] nlohmann::json encode(const ScheduleVersionRecord& version);

}  // namespace sensornet::report
