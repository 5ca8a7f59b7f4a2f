#pragma once
// The account of a run: every finished episode as one entry (the keys of the report's
// `per_episode` and of one line of the JSON Lines episode log), the summary over them, and the
// whole report. The fusion center builds it as episodes finish and appends each entry to the
// episode log at once; the launcher rebuilds the same report from that log when the fusion
// center could not write its own (it died), so no finished episode is ever lost.
//
//   RunReport report(run_id, digest, sensor_count, state_dim, episodeLogPath(path));
//   const nlohmann::json entry = episodeEntry(fusion.finish());
//   log.append(entry);                     // EpisodeLog: one line per episode, flushed
//   report.add(entry);                     // folded into the summary, not kept
//   const nlohmann::json head = report.toJsonWithoutEpisodes(...);
//   writeJsonFile(path, "run report", [&](std::ostream& out) { report.write(out, head, 2); });
//
// Memory stays flat however many episodes a run has: the summary is kept as running sums
// (means, Welford's sum of squares for the interval, per-sensor totals) and the latencies as a
// fixed histogram of fine log-spaced bins (LatencyHistogram: median and p99 within a stated
// relative error); with an episode log the entries are not held but read back from it when the
// report is written (`per_episode` in episode order, each episode once: the first of repeated ones,
// a torn line skipped). Without a log (tests, a fusion center without --report) the entries
// are held.
//
// Statistics (docs/ARCHITECTURE.md): the mean realized cost, its 95% interval and whether it meets the
// mean bracket are over complete episodes only. The interval is Student's t with K - 1 degrees
// of freedom, clipped below at zero (a cost is never negative); with fewer than 2 complete
// episodes there is no interval and `meets_bracket` is undetermined (null in JSON). Counts
// (sent, received, lost, dropped_by_network, late, rejected) are over every episode.

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <istream>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <ostream>
#include <set>
#include <string>
#include <vector>

#include "sensornet/core/chi_square.hpp"
#include "sensornet/core/scenario.hpp"
#include "sensornet/emulator/vocabulary.hpp"
#include "sensornet/emulator/episode_fusion.hpp"
#include "sensornet/emulator/episode_set.hpp"
#include "sensornet/emulator/schedule_book.hpp"
#include "sensornet/report/report_files.hpp"

#include "sensornet/report/run_record.hpp"

namespace sensornet::emulator {

// Many latencies in fixed memory: counts in fine log-spaced bins (kFineBinsPerDecade a decade
// from kLatencyHistogramFloorS up to kLatencyHistogramCeilingS; the floor bin takes anything
// below, the top bin anything above), with the exact count, smallest and largest.
//
//   LatencyHistogram h;
//   h.add(latencies_s);
//   const double median = h.quantile(0.5);   // within kLatencyQuantileRelativeError
//
// quantile(q) is quantile() of the samples (linear interpolation between order statistics) with
// each order statistic replaced by the geometric middle of its bin, clamped to [smallest,
// largest] (the extreme ones are exact): within a factor 10^(1 / (2 kFineBinsPerDecade)) of the
// exact value, i.e. a relative error of at most kLatencyQuantileRelativeError (5.8e-4), for
// latencies between the floor and the ceiling; below the floor the error is at most the floor.
class LatencyHistogram {
 public:
  static constexpr int kFineBinsPerDecade = 2000;  // a multiple of kLatencyBinsPerDecade
  void add(double latency_s);
  void add(const std::vector<double>& latencies_s);
  [[nodiscard]] std::uint64_t count() const noexcept { return count_; }
  [[nodiscard]] double sum() const noexcept { return sum_; }
  [[nodiscard]] double quantile(double q) const;
  // How many latencies are at most `latency_s` (a Prometheus bucket): those of the fine bins
  // wholly below it, exact but for the fine bin it falls in (kLatencyQuantileRelativeError).
  [[nodiscard]] std::uint64_t countAtMost(double latency_s) const;
  // The report's coarse histogram, exactly as latencyHistogram() of the same samples.
  [[nodiscard]] nlohmann::json toJson() const;

 private:
  [[nodiscard]] static std::size_t binOf(double latency_s);
  [[nodiscard]] double orderStatistic(std::uint64_t index) const;
  std::vector<std::uint64_t> counts_;  // fine bins, allocated on the first sample
  std::uint64_t count_ = 0;
  std::size_t lowest_bin_ = 0;
  std::size_t highest_bin_ = 0;
  double smallest_ = 0.0;
  double largest_ = 0.0;
  double sum_ = 0.0;
};

struct RunSummary {
  std::uint32_t episodes = 0;             // finished, complete or not
  std::uint32_t episodes_complete = 0;    // the statistics below are over these
  double mean = 0.0;
  double std_dev = 0.0;
  std::optional<double> ci95;             // half-width t_{0.975,K-1} s / sqrt(K); none for K < 2
  double ci95_low = 0.0;                  // max(0, mean - ci95)
  double ci95_high = 0.0;
  double realtime_mean = 0.0;             // mean real-time cost (EpisodeResult::realtime_cost)
  double received_realtime_mean = 0.0;    // mean of received_realtime_cost where computed (NaN: none)
  CostBracket bracket_mean;
  std::optional<bool> meets_bracket;      // [ci95_low, ci95_high] meets [info, cov]
  CostBracket delivered_bracket_mean;     // of the schedules the emulated network delivered
  std::optional<bool> meets_delivered_bracket;
  double nees_mean = 0.0;
  // The kNeesConfidence band of the mean NEES for n x (complete episodes with a NEES), and
  // whether the mean lies in it (chi_square.hpp); none without such an episode.
  std::optional<NeesBand> nees_band;
  std::optional<bool> nees_consistent;
  std::uint64_t sent = 0;
  std::uint64_t received = 0;
  double expected = 0.0;
  std::uint64_t lost = 0;
  std::uint64_t dropped_by_network = 0;   // by the emulated network: neither received nor lost
  std::uint64_t late = 0;
  std::uint64_t refused = 0;              // sent samples refused as malformed: neither received nor lost
  RejectionCounts rejected;               // by reason, over episodes and the run's wire
  double latency_median_s = 0.0;          // within kLatencyQuantileRelativeError (LatencyHistogram)
  double latency_p99_s = 0.0;
  double network_delay_mean_s = 0.0;      // over the received measurements (emulated seconds)
  double network_delay_max_s = 0.0;
  [[nodiscard]] std::uint64_t rejectedTotal() const;
};

// The per_episode entry of an episode's result (and one line of the episode log). A cost or
// bracket that is not a finite number is null.
[[nodiscard]] nlohmann::json episodeEntry(const EpisodeResult& result);

// The incomplete_reason of an episode the fusion center could not fuse: it restarted during it.
inline constexpr const char* kRestartedReason = "fusion_center_restarted";
// Such an episode's result: incomplete for kRestartedReason, costs and NEES NaN (null in its
// entry), counts zero for `sensor_count` sensors; the caller may fill in versions and brackets.
[[nodiscard]] EpisodeResult restartedEpisode(std::uint32_t episode, int sensor_count);

class RunReport {
 public:
  // One sensor's counts over every episode reported.
  struct SensorTotals {
    std::uint64_t sent = 0, received = 0, lost = 0, dropped_by_network = 0, late = 0,
                  wrong_version = 0, refused = 0;
    double expected = 0.0;
  };
  // Without `episode_log`, holds every entry (for small reports and tests); with it, holds none:
  // `per_episode` is read back from the log (where every added entry was appended) when the
  // report is written.
  RunReport(std::string run_id, std::string scenario_digest, int sensor_count, int state_dim,
            std::optional<std::filesystem::path> episode_log = std::nullopt);

  // An episode entry (episodeEntry, or a line read back from the log).
  void add(const nlohmann::json& entry);
  // The episode log refused `entry` (added already; a full disk): it and every entry added from
  // now on are held here, and `per_episode` is the log's entries followed by these.
  void holdFrom(const nlohmann::json& entry);
  // Publish-to-fusion latencies, for the run's median and p99 (without them, the summary uses
  // the median of the episodes' medians).
  void addLatencies(const std::vector<double>& latencies_s);
  // The latency figures cannot be believed (clocks that disagree): the report gives no median
  // nor p99, and says why.
  void setLatencyUnknown(std::string why) { latency_unknown_because_ = std::move(why); }
  // Samples refused outside any episode (other runs, malformed schedules, ...), by reason.
  void countRejected(const std::string& reason, std::uint64_t count = 1);
  [[nodiscard]] RunSummary summary() const;
  [[nodiscard]] const std::vector<SensorTotals>& sensorTotals() const { return sensor_totals_; }
  [[nodiscard]] const LatencyHistogram& latencies() const { return latencies_; }
  // The whole report. `schedule_versions`: the versions of the run (scheduleVersionsJson);
  // `faults`: a list of {kind, process, sensor, episode, emulated_time_s, detail}.
  [[nodiscard]] nlohmann::json toJson(const std::string& status, const nlohmann::json& faults,
                                      const nlohmann::json& schedule_versions,
                                      const nlohmann::json& extra = nlohmann::json::object()) const;
  // The same without `per_episode`, which write() streams in.
  [[nodiscard]] nlohmann::json toJsonWithoutEpisodes(
      const std::string& status, const nlohmann::json& faults,
      const nlohmann::json& schedule_versions,
      const nlohmann::json& extra = nlohmann::json::object()) const;
  // Writes `doc` (toJsonWithoutEpisodes) with `per_episode` added, entry by entry, as
  // doc.dump(indent) of the whole report would (indent < 0: one line), without holding it.
  void write(std::ostream& out, const nlohmann::json& doc, int indent) const;

 private:
  // Calls `each` with every entry of the report, in order.
  void forEachEpisode(const std::function<void(const nlohmann::json&)>& each) const;

  std::string run_id_;
  std::string digest_;
  int sensor_count_;
  int state_dim_;
  std::optional<std::filesystem::path> episode_log_;
  // Without an episode log: every entry; with one: those it refused (holdFrom) and later ones.
  std::vector<nlohmann::json> episodes_;
  bool holding_ = false;
  // Running sums over every episode (counts) and over complete ones (statistics).
  std::uint32_t episode_count_ = 0;
  std::uint32_t complete_count_ = 0;
  double cost_mean_ = 0.0;     // Welford: the running mean of the realized cost
  double cost_squares_ = 0.0;  // ... and the sum of squared deviations from it
  double realtime_sum_ = 0.0;
  double received_realtime_sum_ = 0.0;
  std::uint32_t received_realtime_count_ = 0;  // complete episodes with it computed
  CostBracket bracket_sum_;
  CostBracket delivered_bracket_sum_;
  double nees_sum_ = 0.0;
  std::uint32_t nees_count_ = 0;  // complete episodes with a NEES (an external one may have none)
  double delay_sum_s_ = 0.0;  // network_delay_mean_s times received, over every episode
  RunSummary summed_;  // its counts (sent, received, lost, ...) over every episode
  RejectionCounts rejected_in_episodes_;

  std::vector<SensorTotals> sensor_totals_;
  LatencyHistogram latencies_;
  std::optional<std::string> latency_unknown_because_;
  LatencyHistogram episode_medians_;  // the fallback without latencies
  RejectionCounts rejected_outside_;
};

// The versions of a run as the report lists them: number, effective point, surrogate, bracket,
// command id, and the schedule itself (horizon_s, rates: N rows of M rates in Hz).
[[nodiscard]] nlohmann::json scheduleVersionsJson(const ScheduleBook& book);

// The report's latency histogram: log-spaced bins, kLatencyBinsPerDecade a decade, from the
// decade below the smallest latency to the one above the largest, as
// {"edges_s": [b_0 .. b_K], "counts": [c_1 .. c_K]}; bin i holds b_i <= latency < b_i+1 (the
// largest latency in the last bin). Latencies below kLatencyHistogramFloorS (a clock step) count
// in the first bin. Null when there are none.
inline constexpr double kLatencyBinsPerDecade = 5.0;
inline constexpr double kLatencyHistogramFloorS = 1e-7;
inline constexpr double kLatencyHistogramCeilingS = 1e4;
inline constexpr double kLatencyQuantileRelativeError = 5.76e-4;  // 10^(1/4000) - 1, rounded up
[[nodiscard]] nlohmann::json latencyHistogram(const std::vector<double>& latencies_s);

// One fault of a run, as the report lists it. Optional parts are none (null) when unknown.
[[nodiscard]] report::FaultRecord faultEntry(FaultKind kind, const std::string& process,
                                        std::optional<int> sensor, std::optional<std::uint32_t> episode,
                                        std::optional<double> emulated_time_s,
                                        const std::string& detail);


// What a restarted fusion center (`serve --resume`) makes of the episodes it hears of. Those in
// its episode log are done: their entries start the report, and their late measurements and
// tallies are ignored. An episode that started before this process joined and is not in the log
// (the one it died in, and any other it cannot have seen whole) cannot be fused: it is recorded
// as restarted (restartedEpisode). Each episode is handed out once.
//
//   ResumedRun resumed(readEpisodeLog(log_path), wallNowNs());
//   for (const auto& entry : resumed.entries()) report.add(entry);
//   for (std::uint32_t e : resumed.heardStart(start.episode, start.clock.start_wall_ns)) ...;
//   if (resumed.ignores(episode)) ...;    // logged or restarted: not fused here
class ResumedRun {
 public:
  ResumedRun(std::vector<nlohmann::json> log_entries, std::int64_t joined_wall_ns);

  // The log's entries, one per episode (the first of repeated ones), in episode order.
  [[nodiscard]] const std::vector<nlohmann::json>& entries() const { return entries_; }
  // The episode is in the log or was recorded as restarted: nothing of it is fused here.
  [[nodiscard]] bool ignores(std::uint32_t episode) const;
  // The start of `episode` was heard: the episodes to record as restarted now (it, if it began
  // before the join and is not logged; the first time, also every earlier one not logged).
  [[nodiscard]] std::vector<std::uint32_t> heardStart(std::uint32_t episode,
                                                      std::int64_t start_wall_ns);
  // A notice about `episode`, which this process never saw start: it is under way and began
  // before the join. The episodes to record as restarted now.
  [[nodiscard]] std::vector<std::uint32_t> heardOfRunning(std::uint32_t episode);
  // The run ended after `episodes_run` episodes: every one not logged nor restarted yet.
  [[nodiscard]] std::vector<std::uint32_t> heardEnd(std::uint32_t episodes_run);
  // This process fused `episode` and logged it.
  void noteFused(std::uint32_t episode) { logged_.insert(episode); }
  // Every episode recorded as restarted so far.
  [[nodiscard]] const std::set<std::uint32_t>& restarted() const { return restarted_; }
  [[nodiscard]] std::int64_t joinedWallNs() const { return joined_wall_ns_; }

 private:
  std::vector<std::uint32_t> restartBefore(std::uint32_t episode);
  std::vector<nlohmann::json> entries_;
  EpisodeSet logged_;
  std::set<std::uint32_t> restarted_;
  std::int64_t joined_wall_ns_;
  bool heard_any_ = false;
};

// A whole report from episode entries (the launcher's rebuild after a fusion center death),
// with the same keys and statistics as the fusion center's (the NEES band needs n, `state_dim`).
[[nodiscard]] nlohmann::json reportFromEpisodes(const std::string& run_id, int sensor_count,
                                                int state_dim,
                                                const std::vector<nlohmann::json>& per_episode,
                                                const std::string& status,
                                                const nlohmann::json& faults);

// The q-quantile (0..1) of values by linear interpolation; 0 when empty.
[[nodiscard]] double quantile(std::vector<double> values, double q);

}  // namespace sensornet::emulator
