#include "sensornet/emulator/run_report.hpp"

#include <algorithm>
#include <cmath>

namespace sensornet::emulator {

double quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const double position = q * static_cast<double>(values.size() - 1);
  const auto below = static_cast<std::size_t>(std::floor(position));
  const std::size_t above = std::min(below + 1, values.size() - 1);
  const double fraction = position - static_cast<double>(below);
  return values[below] + fraction * (values[above] - values[below]);
}

RunReport::RunReport(std::string run_id, std::string scenario_digest, int sensor_count,
                     int state_dim)
    : run_id_(std::move(run_id)),
      digest_(std::move(scenario_digest)),
      sensor_count_(sensor_count),
      state_dim_(state_dim) {}

void RunReport::add(EpisodeResult result) {
  latencies_s_.insert(latencies_s_.end(), result.latencies_s.begin(), result.latencies_s.end());
  result.latencies_s.clear();  // kept once, in latencies_s_
  episodes_.push_back(std::move(result));
}

RunSummary RunReport::summary() const {
  RunSummary s;
  s.episodes = static_cast<std::uint32_t>(episodes_.size());
  if (episodes_.empty()) return s;
  const double k = static_cast<double>(episodes_.size());
  for (const EpisodeResult& e : episodes_) {
    s.mean += e.realized_cost / k;
    s.bracket_mean.info += e.bracket.info / k;
    s.bracket_mean.cov += e.bracket.cov / k;
    s.nees_mean += e.nees / k;
    s.rejected += e.rejected;
    for (const SensorTally& t : e.sensors) {
      s.received += t.received;
      s.expected += t.expected;
      s.lost += t.lost;
      s.late += t.late;
    }
  }
  if (episodes_.size() > 1) {
    double squares = 0.0;
    for (const EpisodeResult& e : episodes_) squares += std::pow(e.realized_cost - s.mean, 2);
    s.std_dev = std::sqrt(squares / (k - 1.0));
    s.ci95 = 1.96 * s.std_dev / std::sqrt(k);
  }
  s.meets_bracket = s.mean - s.ci95 <= s.bracket_mean.cov && s.mean + s.ci95 >= s.bracket_mean.info;
  s.latency_median_s = quantile(latencies_s_, 0.5);
  s.latency_p99_s = quantile(latencies_s_, 0.99);
  return s;
}

nlohmann::json RunReport::toJson(const ScheduleBook& book, const std::string& status,
                                 std::uint64_t rejected_wire) const {
  using nlohmann::json;
  const RunSummary s = summary();
  json versions = json::array();
  for (const ScheduleVersion& v : book.versions()) {
    versions.push_back({{"version", v.version},
                        {"effective_episode", v.effective_episode},
                        {"effective_time_s", v.effective_time_s},
                        {"surrogate", v.surrogate},
                        {"bracket", {{"info", v.bracket.info}, {"cov", v.bracket.cov}}},
                        {"command_id", v.command_id}});
  }
  json per_episode = json::array();
  std::vector<SensorTally> totals(static_cast<std::size_t>(sensor_count_));
  for (const EpisodeResult& e : episodes_) {
    json received = json::array();
    for (std::size_t j = 0; j < e.sensors.size(); ++j) {
      const SensorTally& t = e.sensors[j];
      received.push_back(t.received);
      SensorTally& total = totals[j];
      total.received += t.received;
      total.expected += t.expected;
      total.lost += t.lost;
      total.late += t.late;
      total.wrong_version += t.wrong_version;
    }
    per_episode.push_back({{"episode", e.episode},
                           {"realized_cost", e.realized_cost},
                           {"bracket", {{"info", e.bracket.info}, {"cov", e.bracket.cov}}},
                           {"schedule_versions", e.versions},
                           {"switch_time_s", e.switch_time_s},
                           {"nees", e.nees},
                           {"complete", e.complete},
                           {"received", received}});
  }
  json sensors = json::array();
  for (std::size_t j = 0; j < totals.size(); ++j) {
    const SensorTally& t = totals[j];
    sensors.push_back({{"sensor_id", j},
                       {"received", t.received},
                       {"expected", t.expected},
                       {"lost", t.lost},
                       {"late", t.late},
                       {"wrong_version", t.wrong_version}});
  }
  return {{"run_id", run_id_},
          {"status", status},
          {"scenario", {{"digest", digest_}, {"sensors", sensor_count_}, {"states", state_dim_}}},
          {"episodes", s.episodes},
          {"schedule_versions", versions},
          {"per_episode", per_episode},
          {"summary",
           {{"episodes", s.episodes},
            {"mean", s.mean},
            {"std", s.std_dev},
            {"ci95", s.ci95},
            {"ci95_low", s.mean - s.ci95},
            {"ci95_high", s.mean + s.ci95},
            {"bracket", {{"info", s.bracket_mean.info}, {"cov", s.bracket_mean.cov}}},
            {"meets_bracket", s.meets_bracket},
            {"nees_mean", s.nees_mean},
            {"received", s.received},
            {"expected", s.expected},
            {"lost", s.lost},
            {"late", s.late},
            {"rejected", s.rejected + rejected_wire}}},
          {"sensors", sensors},
          {"latency_s", {{"median", s.latency_median_s}, {"p99", s.latency_p99_s}}}};
}

}  // namespace sensornet::emulator
