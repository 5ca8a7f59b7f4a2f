#include "sensornet/emulator/run_report.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>

#include "sensornet/core/student_t.hpp"

namespace sensornet::emulator {
namespace {

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
json numberOrNull(double value) { return std::isfinite(value) ? json(value) : json(nullptr); }

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
          {"expected", perSensor(r, [](const SensorTally& t) { return t.expected; })},
          {"wrong_version", perSensor(r, [](const SensorTally& t) { return t.wrong_version; })},
          {"rejected", r.rejected},
          {"drain_s", r.drain_s},
          {"backlog", r.backlog},
          {"latency_median_s", quantile(r.latencies_s, 0.5)},
          {"latency_p99_s", quantile(r.latencies_s, 0.99)}};
}

EpisodeResult restartedEpisode(std::uint32_t episode, int sensor_count) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EpisodeResult r;
  r.episode = episode;
  r.realized_cost = r.realtime_cost = r.nees = nan;
  r.bracket = r.delivered_bracket = {nan, nan};
  r.sensors.resize(static_cast<std::size_t>(std::max(sensor_count, 0)));
  r.complete = false;
  r.incomplete_reason = kRestartedReason;
  return r;
}

RunReport::RunReport(std::string run_id, std::string scenario_digest, int sensor_count,
                     int state_dim)
    : run_id_(std::move(run_id)),
      digest_(std::move(scenario_digest)),
      sensor_count_(sensor_count),
      state_dim_(state_dim) {}

void RunReport::add(json entry) { episodes_.push_back(std::move(entry)); }

void RunReport::addLatencies(const std::vector<double>& latencies_s) {
  latencies_s_.insert(latencies_s_.end(), latencies_s.begin(), latencies_s.end());
}

void RunReport::countRejected(const std::string& reason, std::uint64_t count) {
  if (count > 0) rejected_outside_[reason] += count;
}

RunSummary RunReport::summary() const {
  RunSummary s;
  s.episodes = static_cast<std::uint32_t>(episodes_.size());
  s.rejected = rejected_outside_;
  std::vector<double> costs;
  std::vector<double> episode_medians;
  for (const json& e : episodes_) {
    s.sent += sumOf(e.at("sent"));
    s.received += sumOf(e.at("received"));
    s.lost += sumOf(e.at("lost"));
    s.dropped_by_network += sumOf(e.value("dropped_by_network", json::array()));
    s.late += sumOf(e.value("late", json::array()));
    for (const json& x : e.value("expected", json::array())) s.expected += x.get<double>();
    if (const auto rejected = e.find("rejected"); rejected != e.end() && rejected->is_object()) {
      for (const auto& [reason, count] : rejected->items()) {
        s.rejected[reason] += count.get<std::uint64_t>();
      }
    }
    episode_medians.push_back(e.value("latency_median_s", 0.0));
    if (!e.at("complete").get<bool>()) continue;
    costs.push_back(e.at("realized_cost").get<double>());
    s.realtime_mean += e.value("realtime_cost", costs.back());
    addBracket(s.bracket_mean, e.at("bracket"));
    addBracket(s.delivered_bracket_mean, e.value("delivered_bracket", e.at("bracket")));
    s.nees_mean += e.value("nees", 0.0);
  }
  s.episodes_complete = static_cast<std::uint32_t>(costs.size());
  if (!costs.empty()) {
    const double k = static_cast<double>(costs.size());
    for (const double c : costs) s.mean += c / k;
    s.realtime_mean /= k;
    s.bracket_mean.info /= k;
    s.bracket_mean.cov /= k;
    s.delivered_bracket_mean.info /= k;
    s.delivered_bracket_mean.cov /= k;
    s.nees_mean /= k;
    s.ci95_low = s.ci95_high = s.mean;
  }
  if (costs.size() >= 2) {
    const double k = static_cast<double>(costs.size());
    double squares = 0.0;
    for (const double c : costs) squares += (c - s.mean) * (c - s.mean);
    s.std_dev = std::sqrt(squares / (k - 1.0));
    s.ci95 = studentTQuantile(0.975, k - 1.0) * s.std_dev / std::sqrt(k);
    s.ci95_low = std::max(0.0, s.mean - *s.ci95);
    s.ci95_high = s.mean + *s.ci95;
    s.meets_bracket = meets(s, s.bracket_mean);
    s.meets_delivered_bracket = meets(s, s.delivered_bracket_mean);
  }
  if (!latencies_s_.empty()) {
    s.latency_median_s = quantile(latencies_s_, 0.5);
    s.latency_p99_s = quantile(latencies_s_, 0.99);
  } else {
    s.latency_median_s = quantile(episode_medians, 0.5);
    s.latency_p99_s = quantile(episode_medians, 0.99);
  }
  return s;
}

json latencyHistogram(const std::vector<double>& latencies_s) {
  if (latencies_s.empty()) return nullptr;
  const auto [smallest, largest] = std::minmax_element(latencies_s.begin(), latencies_s.end());
  const double floor_s = kLatencyHistogramFloorS;
  const double low = std::floor(std::log10(std::max(*smallest, floor_s)));
  const double high = std::max(low + 1.0, std::ceil(std::log10(std::max(*largest, floor_s)) +
                                                    1e-12));
  const int bins = static_cast<int>(std::lround((high - low) * kLatencyBinsPerDecade));
  json edges = json::array();
  for (int i = 0; i <= bins; ++i) {
    edges.push_back(std::pow(10.0, low + static_cast<double>(i) / kLatencyBinsPerDecade));
  }
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

json RunReport::toJson(const std::string& status, const json& faults,
                       const json& schedule_versions, const json& extra) const {
  const RunSummary s = summary();
  const auto sensors = static_cast<std::size_t>(sensor_count_);
  std::vector<std::uint64_t> sent(sensors), received(sensors), lost(sensors), dropped(sensors),
      late(sensors), wrong(sensors);
  std::vector<double> expected(sensors);
  const auto add = [](auto& totals, const json& values) {
    for (std::size_t j = 0; j < values.size() && j < totals.size(); ++j) {
      totals[j] += values[j].get<typename std::decay_t<decltype(totals)>::value_type>();
    }
  };
  for (const json& e : episodes_) {
    add(sent, e.at("sent"));
    add(received, e.at("received"));
    add(lost, e.at("lost"));
    add(dropped, e.value("dropped_by_network", json::array()));
    add(late, e.value("late", json::array()));
    add(wrong, e.value("wrong_version", json::array()));
    add(expected, e.value("expected", json::array()));
  }
  json per_sensor = json::array();
  for (std::size_t j = 0; j < sensors; ++j) {
    per_sensor.push_back({{"sensor_id", j},
                          {"sent", sent[j]},
                          {"received", received[j]},
                          {"lost", lost[j]},
                          {"dropped_by_network", dropped[j]},
                          {"late", late[j]},
                          {"expected", expected[j]},
                          {"wrong_version", wrong[j]}});
  }
  json report = {
      {"run_id", run_id_},
      {"status", status},
      {"faults", faults.is_array() ? faults : json::array()},
      {"scenario", {{"digest", digest_}, {"sensors", sensor_count_}, {"states", state_dim_}}},
      {"episodes", s.episodes},
      {"schedule_versions", schedule_versions},
      {"per_episode", episodes_},
      {"summary",
       {{"episodes", s.episodes},
        {"episodes_complete", s.episodes_complete},
        {"episodes_incomplete", s.episodes - s.episodes_complete},
        {"mean", s.mean},
        {"std", s.std_dev},
        {"ci95", optionalJson(s.ci95)},
        {"ci95_low", s.ci95_low},
        {"ci95_high", s.ci95_high},
        {"realtime_mean", s.realtime_mean},
        {"bracket", bracketJson(s.bracket_mean)},
        {"meets_bracket", optionalJson(s.meets_bracket)},
        {"delivered_bracket", bracketJson(s.delivered_bracket_mean)},
        {"meets_delivered_bracket", optionalJson(s.meets_delivered_bracket)},
        {"nees_mean", s.nees_mean},
        {"sent", s.sent},
        {"received", s.received},
        {"expected", s.expected},
        {"lost", s.lost},
        {"dropped_by_network", s.dropped_by_network},
        {"late", s.late},
        {"rejected", s.rejectedTotal()},
        {"rejected_by_reason", s.rejected}}},
      {"sensors", per_sensor},
      {"latency_s",
       {{"median", s.latency_median_s},
        {"p99", s.latency_p99_s},
        {"histogram", latencyHistogram(latencies_s_)}}}};
  for (const auto& [key, value] : extra.items()) report[key] = value;
  return report;
}

json faultEntry(const std::string& kind, const std::string& process, std::optional<int> sensor,
                std::optional<std::uint32_t> episode, std::optional<double> emulated_time_s,
                const std::string& detail) {
  return {{"kind", kind},
          {"process", process},
          {"sensor", sensor ? json(*sensor) : json(nullptr)},
          {"episode", episode ? json(*episode) : json(nullptr)},
          {"emulated_time_s", optionalJson(emulated_time_s)},
          {"detail", detail}};
}

std::filesystem::path episodeLogPath(const std::filesystem::path& report_path) {
  std::filesystem::path log = report_path;
  if (log.extension() == ".json") return log.replace_extension(".jsonl");
  return log += ".jsonl";
}

namespace {

// The file is not empty and its last byte is not a newline: a line torn by a crash.
bool endsInTornLine(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in || in.tellg() <= 0) return false;
  in.seekg(-1, std::ios::end);
  char last = '\n';
  in.get(last);
  return last != '\n';
}

}  // namespace

EpisodeLog::EpisodeLog(const std::filesystem::path& path, Mode mode) : path_(path) {
  const bool torn = mode == Mode::Append && endsInTornLine(path);
  out_.open(path, mode == Mode::Append ? std::ios::app : std::ios::trunc);
  if (!out_) throw std::runtime_error("cannot write the episode log " + path.string());
  if (torn) {
    out_ << '\n';  // the torn line stays a line of its own, which readEpisodeLog skips
    out_.flush();
  }
}

void EpisodeLog::append(const json& entry) {
  out_ << entry.dump() << '\n';
  out_.flush();
  if (!out_) throw std::runtime_error("cannot append to the episode log " + path_.string());
}

std::vector<json> readEpisodeLog(const std::filesystem::path& path) {
  std::vector<json> entries;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    json entry = json::parse(line, nullptr, false);
    if (entry.is_object() && entry.contains("episode")) entries.push_back(std::move(entry));
  }
  return entries;
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

json reportFromEpisodes(const std::string& run_id, int sensor_count,
                        const std::vector<json>& per_episode, const std::string& status,
                        const json& faults) {
  RunReport report(run_id, "", sensor_count, 0);
  for (const json& entry : per_episode) report.add(entry);
  return report.toJson(status, faults, json::array(),
                       {{"rebuilt_from", "episode log (the fusion center wrote no report)"}});
}

}  // namespace sensornet::emulator
