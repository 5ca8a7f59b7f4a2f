#pragma once
// The fusion center's account of a run: every episode's result, and the running summary
// (mean realized cost with its 95% interval against the mean bracket in force, NEES, counts,
// latency). It fills the Report topic after each episode and writes the final JSON report.
//
//   RunReport report(run_id, digest, scenario);
//   report.add(fusion.finish());
//   fillReport(sample, storage, report);   // the DDS Report of the last episode
//   writeJsonFile(path, report.toJson(book));

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "sensornet/core/scenario.hpp"
#include "sensornet/emulator/episode_fusion.hpp"
#include "sensornet/emulator/schedule_book.hpp"

namespace sensornet::emulator {

struct RunSummary {
  std::uint32_t episodes = 0;
  double mean = 0.0;
  double std_dev = 0.0;
  double ci95 = 0.0;  // 1.96 s / sqrt(K)
  CostBracket bracket_mean;
  bool meets_bracket = false;  // [mean - ci95, mean + ci95] meets [info, cov]
  double nees_mean = 0.0;
  std::uint64_t received = 0;
  double expected = 0.0;
  std::uint64_t lost = 0;
  std::uint64_t late = 0;
  std::uint64_t rejected = 0;
  double latency_median_s = 0.0;
  double latency_p99_s = 0.0;
};

class RunReport {
 public:
  RunReport(std::string run_id, std::string scenario_digest, int sensor_count, int state_dim);

  void add(EpisodeResult result);
  [[nodiscard]] const std::vector<EpisodeResult>& episodes() const { return episodes_; }
  [[nodiscard]] RunSummary summary() const;
  // rejected_wire: samples refused on the wire (malformed, stale schedules, foreign runs).
  [[nodiscard]] nlohmann::json toJson(const ScheduleBook& book, const std::string& status,
                                      std::uint64_t rejected_wire) const;

 private:
  std::string run_id_;
  std::string digest_;
  int sensor_count_;
  int state_dim_;
  std::vector<EpisodeResult> episodes_;
  std::vector<double> latencies_s_;
};

// The q-quantile (0..1) of values by linear interpolation; 0 when empty.
[[nodiscard]] double quantile(std::vector<double> values, double q);

}  // namespace sensornet::emulator
