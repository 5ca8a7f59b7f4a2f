#include "sensornet/emulator/run_report.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <deque>
#include <map>
#include <stdexcept>

#include "sensornet/core/student_t.hpp"
#include "sensornet/report/run_record.hpp"
#include "sensornet/report/report_files.hpp"

namespace sensornet::emulator {
namespace {

using sensornet::report::forEachReportedEpisode;

using nlohmann::json;

// One value per sensor of an episode's tallies.
template <typename Field>
json perSensor(const EpisodeResult& r, Field field) {
  json values = json::array();
  for (const SensorTally& t : r.sensors) values.push_back(field(t));
  return values;
}

std::uint64_t sumOf(const json& values) {
  std::uint64_t total = 0;
  for (const json& v : values) total += v.get<std::uint64_t>();
  return total;
}

json optionalJson(const std::optional<double>& value) {
  return value ? json(*value) : json(nullptr);
}

json optionalJson(const std::optional<bool>& value) {
  return value ? json(*value) : json(nullptr);
}

// A number, or null when it is not finite (an episode that could not be fused).
using sensornet::report::kPerEpisode;

json numberOrNull(double value) { return std::isfinite(value) ? json(value) : json(nullptr); }

// The number at `key`, nullopt when the entry has none or null there (not computed: an external
// fusion center's NEES, say).
std::optional<double> numberAt(const json& e, const char* key) {
  const auto it = e.find(key);
  if (it == e.end() || it->is_null()) return std::nullopt;
  return it->get<double>();
}

// A sum of many expected counts to 12 significant digits: the summation's rounding error
// (216 printed as 215.99999999997434) is not part of the number.
double roundedSum(double sum) {
  char text[32];
  std::snprintf(text, sizeof text, "%.12g", sum);
  return std::strtod(text, nullptr);
}

json bracketJson(const CostBracket& b) {
  return {{"info", numberOrNull(b.info)}, {"cov", numberOrNull(b.cov)}};
}

void addBracket(CostBracket& sum, const json& b) {
  sum.info += b.at("info").get<double>();
  sum.cov += b.at("cov").get<double>();
}

// The 95% interval of the mean meets the bracket.
bool meets(const RunSummary& s, const CostBracket& bracket) {
  return s.ci95_low <= bracket.cov && s.ci95_high >= bracket.info;
}

}  // namespace

double quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const double position = q * static_cast<double>(values.size() - 1);
  const auto below = static_cast<std::size_t>(std::floor(position));
  const std::size_t above = std::min(below + 1, values.size() - 1);
  const double fraction = position - static_cast<double>(below);
  return values[below] + fraction * (values[above] - values[below]);
}

std::uint64_t RunSummary::rejectedTotal() const {
  std::uint64_t total = 0;
  for (const auto& [reason, count] : rejected) total += count;
  return total;
}

json episodeEntry(const EpisodeResult& r) {
  return {{"episode", r.episode},
          {"realized_cost", numberOrNull(r.realized_cost)},
          {"realtime_cost", numberOrNull(r.realtime_cost)},
          {"received_realtime_cost", numberOrNull(r.received_realtime_cost)},
          {"bracket", bracketJson(r.bracket)},
          {"delivered_bracket", bracketJson(r.delivered_bracket)},
          {"schedule_versions", r.versions},
          {"switch_time_s", r.switch_time_s},
          {"nees", numberOrNull(r.nees)},
          {"complete", r.complete},
          {"incomplete_reason", r.complete ? json(nullptr) : json(r.incomplete_reason)},
          {"failed_sensors", r.failed_sensors},
          {"sent", perSensor(r, [](const SensorTally& t) { return t.sent; })},
          {"received", perSensor(r, [](const SensorTally& t) { return t.received; })},
          {"lost", perSensor(r, [](const SensorTally& t) { return t.lost; })},
          {"dropped_by_network",
           perSensor(r, [](const SensorTally& t) { return t.dropped_by_network; })},
          {"late", perSensor(r, [](const SensorTally& t) { return t.late; })},
          {"refused", perSensor(r, [](const SensorTally& t) { return t.refused; })},
          {"expected", perSensor(r, [](const SensorTally& t) { return t.expected; })},
          {"wrong_version", perSensor(r, [](const SensorTally& t) { return t.wrong_version; })},
          {"rejected", r.rejected},
          {"drain_s", r.drain_s},
          {"backlog", r.backlog},
          // None measured (or none believed: clocks that disagree): null, not 0.
          {"latency_median_s", r.latencies_s.empty() ? json(nullptr) : json(quantile(r.latencies_s, 0.5))},
          {"latency_p99_s", r.latencies_s.empty() ? json(nullptr) : json(quantile(r.latencies_s, 0.99))},
          {"network_delay_mean_s", r.network_delay_mean_s},
          {"network_delay_max_s", r.network_delay_max_s}};
}

EpisodeResult restartedEpisode(std::uint32_t episode, int sensor_count) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EpisodeResult r;
  r.episode = episode;
  r.realized_cost = r.realtime_cost = r.received_realtime_cost = r.nees = nan;
  r.bracket = r.delivered_bracket = {nan, nan};
  r.sensors.resize(static_cast<std::size_t>(std::max(sensor_count, 0)));
  r.complete = false;
  r.incomplete_reason = kRestartedReason;
  return r;
}

RunReport::RunReport(std::string run_id, std::string scenario_digest, int sensor_count,
                     int state_dim, std::optional<std::filesystem::path> episode_log)
    : run_id_(std::move(run_id)),
      digest_(std::move(scenario_digest)),
      sensor_count_(sensor_count),
      state_dim_(state_dim),
      episode_log_(std::move(episode_log)),
      sensor_totals_(static_cast<std::size_t>(std::max(sensor_count, 0))) {}

void RunReport::holdFrom(const json& entry) {
  if (!holding_) episodes_.push_back(entry);
  holding_ = true;
}

void RunReport::add(const json& e) {
  if (!episode_log_ || holding_) episodes_.push_back(e);
  ++episode_count_;
  const json none = json::array();
  // An entry's per-sensor values onto the totals (an entry may list fewer or more sensors).
  const auto addPerSensor = [](std::vector<SensorTotals>& totals, const json& values,
                               auto member) {
    if (!values.is_array()) return;
    for (std::size_t j = 0; j < values.size() && j < totals.size(); ++j) {
      auto& total = totals[j].*member;
      total += values[j].get<std::remove_reference_t<decltype(total)>>();
    }
  };
  addPerSensor(sensor_totals_, e.at("sent"), &SensorTotals::sent);
  addPerSensor(sensor_totals_, e.at("received"), &SensorTotals::received);
  addPerSensor(sensor_totals_, e.at("lost"), &SensorTotals::lost);
  addPerSensor(sensor_totals_, e.value("dropped_by_network", none),
               &SensorTotals::dropped_by_network);
  addPerSensor(sensor_totals_, e.value("late", none), &SensorTotals::late);
  addPerSensor(sensor_totals_, e.value("refused", none), &SensorTotals::refused);
  addPerSensor(sensor_totals_, e.value("wrong_version", none), &SensorTotals::wrong_version);
  addPerSensor(sensor_totals_, e.value("expected", none), &SensorTotals::expected);
  summed_.sent += sumOf(e.at("sent"));
  summed_.received += sumOf(e.at("received"));
  summed_.lost += sumOf(e.at("lost"));
  summed_.dropped_by_network += sumOf(e.value("dropped_by_network", none));
  summed_.late += sumOf(e.value("late", none));
  summed_.refused += sumOf(e.value("refused", none));
  for (const json& x : e.value("expected", none)) summed_.expected += x.get<double>();
  if (const auto rejected = e.find("rejected"); rejected != e.end() && rejected->is_object()) {
    for (const auto& [reason, count] : rejected->items()) {
      rejected_in_episodes_[reason] += count.get<std::uint64_t>();
    }
  }
  if (const auto median = numberAt(e, "latency_median_s")) episode_medians_.add(*median);
  const auto received_count = static_cast<double>(sumOf(e.at("received")));
  delay_sum_s_ += e.value("network_delay_mean_s", 0.0) * received_count;
  summed_.network_delay_max_s =
      std::max(summed_.network_delay_max_s, e.value("network_delay_max_s", 0.0));
  if (!e.at("complete").get<bool>()) return;
  const double cost = e.at("realized_cost").get<double>();
  ++complete_count_;
  const double delta = cost - cost_mean_;  // Welford's update
  cost_mean_ += delta / static_cast<double>(complete_count_);
  cost_squares_ += delta * (cost - cost_mean_);
  realtime_sum_ += numberAt(e, "realtime_cost").value_or(cost);
  if (const auto received = e.find("received_realtime_cost");
      received == e.end() || received->is_number()) {  // null: not computed (overload)
    received_realtime_sum_ += received == e.end() ? e.value("realtime_cost", cost)
                                                  : received->get<double>();
    ++received_realtime_count_;
  }
  addBracket(bracket_sum_, e.at("bracket"));
  addBracket(delivered_bracket_sum_, e.value("delivered_bracket", e.at("bracket")));
  if (const auto nees = numberAt(e, "nees")) {
    nees_sum_ += *nees;
    ++nees_count_;
  }
}

void RunReport::addLatencies(const std::vector<double>& latencies_s) { latencies_.add(latencies_s); }

void RunReport::countRejected(const std::string& reason, std::uint64_t count) {
  if (count > 0) rejected_outside_[reason] += count;
}

RunSummary RunReport::summary() const {
  RunSummary s = summed_;
  s.episodes = episode_count_;
  s.episodes_complete = complete_count_;
  s.rejected = rejected_outside_;
  for (const auto& [reason, count] : rejected_in_episodes_) s.rejected[reason] += count;
  if (complete_count_ > 0) {
    const double k = static_cast<double>(complete_count_);
    s.mean = cost_mean_;
    s.realtime_mean = realtime_sum_ / k;
    s.received_realtime_mean =
        received_realtime_count_ > 0
            ? received_realtime_sum_ / static_cast<double>(received_realtime_count_)
            : std::numeric_limits<double>::quiet_NaN();
    s.bracket_mean = {bracket_sum_.info / k, bracket_sum_.cov / k};
    s.delivered_bracket_mean = {delivered_bracket_sum_.info / k, delivered_bracket_sum_.cov / k};
    s.nees_mean = nees_count_ > 0 ? nees_sum_ / static_cast<double>(nees_count_)
                                  : std::numeric_limits<double>::quiet_NaN();
    if (nees_count_ > 0 && state_dim_ > 0 && std::isfinite(s.nees_mean)) {
      s.nees_band = neesBand(state_dim_, nees_count_, kNeesConfidence);
      s.nees_consistent = s.nees_band->holds(s.nees_mean);
    }
    s.ci95_low = s.ci95_high = s.mean;
  }
  if (complete_count_ >= 2) {
    const double k = static_cast<double>(complete_count_);
    s.std_dev = std::sqrt(cost_squares_ / (k - 1.0));
    s.ci95 = studentTQuantile(0.975, k - 1.0) * s.std_dev / std::sqrt(k);
    s.ci95_low = std::max(0.0, s.mean - *s.ci95);
    s.ci95_high = s.mean + *s.ci95;
    s.meets_bracket = meets(s, s.bracket_mean);
    s.meets_delivered_bracket = meets(s, s.delivered_bracket_mean);
  }
  if (s.received > 0) s.network_delay_mean_s = delay_sum_s_ / static_cast<double>(s.received);
  const LatencyHistogram& latencies = latencies_.count() > 0 ? latencies_ : episode_medians_;
  s.latency_median_s = latencies.quantile(0.5);
  s.latency_p99_s = latencies.quantile(0.99);
  return s;
}

namespace {

// The decades of the report's coarse histogram: from the one below the smallest latency to the
// one above the largest.
std::pair<double, double> histogramDecades(double smallest, double largest) {
  const double floor_s = kLatencyHistogramFloorS;
  const double low = std::floor(std::log10(std::max(smallest, floor_s)));
  const double high =
      std::max(low + 1.0, std::ceil(std::log10(std::max(largest, floor_s)) + 1e-12));
  return {low, high};
}

json histogramEdges(double low, int bins) {
  json edges = json::array();
  for (int i = 0; i <= bins; ++i) {
    edges.push_back(std::pow(10.0, low + static_cast<double>(i) / kLatencyBinsPerDecade));
  }
  return edges;
}

constexpr double kFineBinsPerDecade = LatencyHistogram::kFineBinsPerDecade;
const double kFloorDecade = std::log10(kLatencyHistogramFloorS);
const auto kFineBins = static_cast<std::size_t>(
    std::lround((std::log10(kLatencyHistogramCeilingS) - kFloorDecade) * kFineBinsPerDecade));

}  // namespace

std::size_t LatencyHistogram::binOf(double latency_s) {
  const double position =
      (std::log10(std::max(latency_s, kLatencyHistogramFloorS)) - kFloorDecade) *
      kFineBinsPerDecade;
  return static_cast<std::size_t>(
      std::clamp(std::floor(position), 0.0, static_cast<double>(kFineBins - 1)));
}

void LatencyHistogram::add(double latency_s) {
  if (counts_.empty()) {
    counts_.assign(kFineBins, 0);
    smallest_ = largest_ = latency_s;
    lowest_bin_ = highest_bin_ = binOf(latency_s);
  }
  const std::size_t bin = binOf(latency_s);
  ++counts_[bin];
  ++count_;
  sum_ += latency_s;
  smallest_ = std::min(smallest_, latency_s);
  largest_ = std::max(largest_, latency_s);
  lowest_bin_ = std::min(lowest_bin_, bin);
  highest_bin_ = std::max(highest_bin_, bin);
}

std::uint64_t LatencyHistogram::countAtMost(double latency_s) const {
  if (count_ == 0 || latency_s < smallest_) return 0;
  if (latency_s >= largest_) return count_;
  const std::size_t bin = binOf(latency_s);
  std::uint64_t n = 0;
  for (std::size_t b = lowest_bin_; b < bin && b <= highest_bin_; ++b) n += counts_[b];
  return n;
}

void LatencyHistogram::add(const std::vector<double>& latencies_s) {
  for (const double latency : latencies_s) add(latency);
}

double LatencyHistogram::orderStatistic(std::uint64_t index) const {
  if (index == 0) return smallest_;
  if (index + 1 >= count_) return largest_;
  std::uint64_t below = 0;
  std::size_t bin = lowest_bin_;
  for (; bin < highest_bin_; ++bin) {
    below += counts_[bin];
    if (below > index) break;
  }
  const double middle =
      std::pow(10.0, kFloorDecade + (static_cast<double>(bin) + 0.5) / kFineBinsPerDecade);
  return std::clamp(middle, smallest_, largest_);
}

double LatencyHistogram::quantile(double q) const {
  if (count_ == 0) return 0.0;
  const double position = q * static_cast<double>(count_ - 1);
  const auto below = static_cast<std::uint64_t>(std::floor(position));
  const std::uint64_t above = std::min(below + 1, count_ - 1);
  const double fraction = position - static_cast<double>(below);
  const double low = orderStatistic(below);
  return fraction == 0.0 ? low : low + fraction * (orderStatistic(above) - low);
}

json LatencyHistogram::toJson() const {
  if (count_ == 0) return nullptr;
  const auto [low, high] = histogramDecades(smallest_, largest_);
  const int bins = static_cast<int>(std::lround((high - low) * kLatencyBinsPerDecade));
  std::vector<std::uint64_t> counts(static_cast<std::size_t>(bins), 0);
  // Fine bins nest in coarse ones: kFineBinsPerDecade / kLatencyBinsPerDecade fine a coarse.
  const auto per_coarse = static_cast<std::size_t>(kFineBinsPerDecade / kLatencyBinsPerDecade);
  const auto offset = static_cast<std::ptrdiff_t>(
      std::lround((kFloorDecade - low) * kLatencyBinsPerDecade));
  for (std::size_t bin = lowest_bin_; bin <= highest_bin_; ++bin) {
    if (counts_[bin] == 0) continue;
    const std::ptrdiff_t coarse = static_cast<std::ptrdiff_t>(bin / per_coarse) + offset;
    counts[static_cast<std::size_t>(std::clamp<std::ptrdiff_t>(coarse, 0, bins - 1))] +=
        counts_[bin];
  }
  return {{"edges_s", histogramEdges(low, bins)}, {"counts", counts}};
}

json latencyHistogram(const std::vector<double>& latencies_s) {
  if (latencies_s.empty()) return nullptr;
  const auto [smallest, largest] = std::minmax_element(latencies_s.begin(), latencies_s.end());
  const double floor_s = kLatencyHistogramFloorS;
  const auto [low, high] = histogramDecades(*smallest, *largest);
  const int bins = static_cast<int>(std::lround((high - low) * kLatencyBinsPerDecade));
  const json edges = histogramEdges(low, bins);
  std::vector<std::uint64_t> counts(static_cast<std::size_t>(bins), 0);
  for (const double latency : latencies_s) {
    const double position =
        (std::log10(std::max(latency, floor_s)) - low) * kLatencyBinsPerDecade;
    const auto bin = static_cast<std::size_t>(std::clamp(std::floor(position), 0.0,
                                                         static_cast<double>(bins - 1)));
    ++counts[bin];
  }
  return {{"edges_s", edges}, {"counts", counts}};
}

json scheduleVersionsJson(const ScheduleBook& book) {
  json versions = json::array();
  for (const ScheduleVersion& v : book.versions()) {
    json rates = json::array();
    for (int k = 0; k < v.schedule.intervals(); ++k) {
      json row = json::array();
      for (int j = 0; j < v.schedule.sensorCount(); ++j) row.push_back(v.schedule.rate(k, j));
      rates.push_back(std::move(row));
    }
    versions.push_back({{"version", v.version},
                        {"effective_episode", v.effective_episode},
                        {"effective_time_s", v.effective_time_s},
                        {"surrogate", v.surrogate},
                        {"bracket", {{"info", v.bracket.info}, {"cov", v.bracket.cov}}},
                        {"command_id", v.command_id},
                        {"horizon_s", v.schedule.horizon()},
                        {"rates", rates}});
  }
  return versions;
}

json RunReport::toJsonWithoutEpisodes(const std::string& status, const json& faults,
                                      const json& schedule_versions, const json& extra) const {
  const RunSummary s = summary();
  json per_sensor = json::array();
  for (std::size_t j = 0; j < sensor_totals_.size(); ++j) {
    const SensorTotals& t = sensor_totals_[j];
    per_sensor.push_back({{"sensor_id", j},
                          {"sent", t.sent},
                          {"received", t.received},
                          {"lost", t.lost},
                          {"dropped_by_network", t.dropped_by_network},
                          {"late", t.late},
                          {"refused", t.refused},
                          {"expected", t.expected},
                          {"wrong_version", t.wrong_version}});
  }
  // Nothing that was not measured is a number: no mean without a complete episode, no spread
  // without two, no latency without a measurement (null, which every reader shows as such).
  const auto ofComplete = [&s](double value, std::uint64_t needed = 1) {
    return s.episodes_complete >= needed ? numberOrNull(value) : json(nullptr);
  };
  const bool measured_latency = latencies_.count() > 0 && !latency_unknown_because_;
  json report = {
      {"schema_version", sensornet::report::kRecordSchemaVersion},
      {"run_id", run_id_},
      {"status", status},
      {"faults", faults.is_array() ? faults : json::array()},
      {"scenario", {{"digest", digest_}, {"sensors", sensor_count_}, {"states", state_dim_}}},
      {"episodes", s.episodes},
      {"schedule_versions", schedule_versions},
      {"summary",
       {{"episodes", s.episodes},
        {"episodes_complete", s.episodes_complete},
        {"episodes_incomplete", s.episodes - s.episodes_complete},
        {"mean", ofComplete(s.mean)},
        {"std", ofComplete(s.std_dev, 2)},
        {"ci95", optionalJson(s.ci95)},
        {"ci95_low", ofComplete(s.ci95_low, 2)},
        {"ci95_high", ofComplete(s.ci95_high, 2)},
        {"realtime_mean", ofComplete(s.realtime_mean)},
        {"received_realtime_mean", ofComplete(s.received_realtime_mean)},
        {"bracket", s.episodes_complete > 0 ? bracketJson(s.bracket_mean) : json(nullptr)},
        {"meets_bracket", optionalJson(s.meets_bracket)},
        {"delivered_bracket",
         s.episodes_complete > 0 ? bracketJson(s.delivered_bracket_mean) : json(nullptr)},
        {"meets_delivered_bracket", optionalJson(s.meets_delivered_bracket)},
        {"nees_mean", ofComplete(s.nees_mean)},
        {"nees_band_low", s.nees_band ? json(s.nees_band->low) : json(nullptr)},
        {"nees_band_high", s.nees_band ? json(s.nees_band->high) : json(nullptr)},
        {"nees_confidence", kNeesConfidence},
        {"nees_consistent", optionalJson(s.nees_consistent)},
        {"sent", s.sent},
        {"received", s.received},
        {"expected", roundedSum(s.expected)},
        {"lost", s.lost},
        {"dropped_by_network", s.dropped_by_network},
        {"late", s.late},
        {"refused", s.refused},
        {"rejected", s.rejectedTotal()},
        {"rejected_by_reason", s.rejected}}},
      {"sensors", per_sensor},
      {"latency_s",
       {{"median", measured_latency ? numberOrNull(s.latency_median_s) : json(nullptr)},
        {"p99", measured_latency ? numberOrNull(s.latency_p99_s) : json(nullptr)},
        {"quantile_relative_error", kLatencyQuantileRelativeError},
        {"histogram", latencies_.toJson()}}},
      // Apart from the latency: emulated seconds the emulated network held the received back.
      {"network_delay_s",
       {{"mean", s.received > 0 ? json(s.network_delay_mean_s) : json(nullptr)},
        {"max", s.received > 0 ? json(s.network_delay_max_s) : json(nullptr)}}}};
  if (latency_unknown_because_) report["latency_s"]["unknown_because"] = *latency_unknown_because_;
  for (const auto& [key, value] : extra.items()) report[key] = value;
  report.erase(kPerEpisode);
  return report;
}

json RunReport::toJson(const std::string& status, const json& faults,
                       const json& schedule_versions, const json& extra) const {
  json report = toJsonWithoutEpisodes(status, faults, schedule_versions, extra);
  json& per_episode = report[kPerEpisode] = json::array();
  forEachEpisode([&per_episode](const json& entry) { per_episode.push_back(entry); });
  return report;
}

void RunReport::forEachEpisode(const std::function<void(const json&)>& each) const {
  if (episode_log_ && episodes_.empty()) {
    forEachReportedEpisode(*episode_log_, each);
    return;
  }
  // As from a log: in episode order, the first of repeated ones (the log's before those held).
  std::deque<json> logged;
  std::map<std::uint32_t, const json*> by_episode;
  if (episode_log_) {
    forEachReportedEpisode(*episode_log_, [&](const json& entry) {
      logged.push_back(entry);
      by_episode.emplace(entry.at("episode").get<std::uint32_t>(), &logged.back());
    });
  }
  for (const json& entry : episodes_) {
    by_episode.emplace(entry.at("episode").get<std::uint32_t>(), &entry);
  }
  for (const auto& [episode, entry] : by_episode) each(*entry);
}

void RunReport::write(std::ostream& out, const json& doc, int indent) const {
  sensornet::report::writeReportWith(
      out, doc, [this](const std::function<void(const json&)>& each) { forEachEpisode(each); },
      indent);
}

report::FaultRecord faultEntry(FaultKind kind, const std::string& process,
                               std::optional<int> sensor, std::optional<std::uint32_t> episode,
                               std::optional<double> emulated_time_s, const std::string& detail) {
  report::FaultRecord fault;
  fault.kind = kind;
  fault.process = process;
  fault.sensor = sensor;
  fault.episode = episode;
  if (emulated_time_s && std::isfinite(*emulated_time_s)) fault.emulated_time_s = emulated_time_s;
  fault.detail = detail;
  return fault;
}

ResumedRun::ResumedRun(std::vector<json> log_entries, std::int64_t joined_wall_ns)
    : joined_wall_ns_(joined_wall_ns) {
  std::map<std::uint32_t, json> by_episode;
  for (json& entry : log_entries) {
    const json& number = entry.at("episode");
    if (!number.is_number_unsigned()) continue;
    by_episode.emplace(number.get<std::uint32_t>(), std::move(entry));
  }
  for (auto& [episode, entry] : by_episode) {
    logged_.insert(episode);
    entries_.push_back(std::move(entry));
  }
}

bool ResumedRun::ignores(std::uint32_t episode) const {
  return logged_.count(episode) > 0 || restarted_.count(episode) > 0;
}

std::vector<std::uint32_t> ResumedRun::restartBefore(std::uint32_t episode) {
  std::vector<std::uint32_t> restarted;
  if (heard_any_) return restarted;
  heard_any_ = true;
  for (std::uint32_t k = 0; k < episode; ++k) {
    if (!ignores(k)) {
      restarted_.insert(k);
      restarted.push_back(k);
    }
  }
  return restarted;
}

std::vector<std::uint32_t> ResumedRun::heardStart(std::uint32_t episode,
                                                  std::int64_t start_wall_ns) {
  std::vector<std::uint32_t> restarted = restartBefore(episode);
  if (start_wall_ns < joined_wall_ns_ && !ignores(episode)) {
    restarted_.insert(episode);
    restarted.push_back(episode);
  }
  return restarted;
}

std::vector<std::uint32_t> ResumedRun::heardOfRunning(std::uint32_t episode) {
  std::vector<std::uint32_t> restarted = restartBefore(episode);
  if (!ignores(episode)) {
    restarted_.insert(episode);
    restarted.push_back(episode);
  }
  return restarted;
}

std::vector<std::uint32_t> ResumedRun::heardEnd(std::uint32_t episodes_run) {
  std::vector<std::uint32_t> restarted;
  for (std::uint32_t k = 0; k < episodes_run; ++k) {
    if (!ignores(k)) {
      restarted_.insert(k);
      restarted.push_back(k);
    }
  }
  return restarted;
}

json reportFromEpisodes(const std::string& run_id, int sensor_count, int state_dim,
                        const std::vector<json>& per_episode, const std::string& status,
                        const json& faults) {
  RunReport report(run_id, "", sensor_count, state_dim);
  for (const json& entry : per_episode) report.add(entry);
  return report.toJson(status, faults, json::array(),
                       {{"rebuilt_from", "episode log (the fusion center wrote no report)"}});
}

}  // namespace sensornet::emulator
