#include "sensornet/wire/messages.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <limits>
#include <vector>
#include <algorithm>

#include "sensornet/core/arrival_mode.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/dds/wire.hpp"
#include "sensornet/io/scenario_file.hpp"

namespace sensornet::wire {

using namespace sensornet::emulator;  // the core types this file encodes and decodes

namespace {

using dds::borrowSequence;
using dds::borrowString;
using dds::viewSequence;
using dds::viewString;

}  // namespace

void withScenarioSample(const std::string& run_id, const RunScenario& scenario,
                        const std::function<void(const sensornet_Scenario&)>& use) {
  sensornet_Scenario sample{};
  sample.run_id = borrowString(run_id);
  sample.digest = borrowString(scenario.digest);
  sample.yaml = borrowString(scenario.yaml);
  sample.horizon_s = scenario.scenario.horizon_s;
  sample.intervals = static_cast<std::uint32_t>(scenario.scenario.intervals);
  sample.sensor_count = static_cast<std::uint32_t>(scenario.scenario.sensorCount());
  sample.state_dim = static_cast<std::uint32_t>(scenario.scenario.stateDim());
  sample.seed = scenario.seed;
  const std::string arrivals(wordOf(scenario.scenario.arrivals));
  sample.arrivals = borrowString(arrivals);
  use(sample);
}

dds::WriteResult publishScenario(dds::Writer<sensornet_Scenario>& writer,
                                 const std::string& run_id, const RunScenario& scenario) {
  dds::WriteResult result = dds::WriteResult::TimedOut;
  withScenarioSample(run_id, scenario, [&](const sensornet_Scenario& s) { result = writer.write(s); });
  return result;
}

RunScenario scenarioFromWire(const sensornet_Scenario& sample) {
  const std::string source = "DDS Scenario";
  RunScenario result;
  result.yaml = std::string(viewString(sample.yaml));
  result.digest = std::string(viewString(sample.digest));
  result.seed = sample.seed;
  if (digestOf(result.yaml) != result.digest) {
    throw InputError(source, "digest", "the digest of the YAML text (" + digestOf(result.yaml) +
                                           "), got '" + result.digest + "'");
  }
  result.scenario = parseScenarioYaml(result.yaml, source);
  const Scenario& s = result.scenario;
  if (s.stateDim() != static_cast<int>(sample.state_dim) ||
      s.sensorCount() != static_cast<int>(sample.sensor_count) ||
      s.intervals != static_cast<int>(sample.intervals) || s.horizon_s != sample.horizon_s) {
    throw InputError(source, "state_dim/sensor_count/intervals/horizon_s",
                     "the dimensions of the YAML it carries");
  }
  // The mode in force is the one announced, not the YAML's (--arrivals overrides it). The field
  // was appended to the IDL; a writer that leaves it empty runs Poisson arrivals, as before it.
  const std::string_view arrivals = viewString(sample.arrivals);
  result.scenario.arrivals = arrivals.empty()
                                 ? ArrivalMode::Poisson
                                 : parseWord<ArrivalMode>(arrivals, source, "arrivals");
  return result;
}

void withScheduleSample(const std::string& run_id, const std::string& scenario_digest,
                        const ScheduleVersion& version,
                        const std::function<void(const sensornet_Schedule&)>& use) {
  const RateSchedule& schedule = version.schedule;
  // Row-major N x M.
  std::vector<double> rates(static_cast<std::size_t>(schedule.intervals() * schedule.sensorCount()));
  for (int k = 0; k < schedule.intervals(); ++k) {
    for (int j = 0; j < schedule.sensorCount(); ++j) {
      rates[static_cast<std::size_t>(k * schedule.sensorCount() + j)] = schedule.rate(k, j);
    }
  }
  sensornet_Schedule sample{};
  sample.run_id = borrowString(run_id);
  sample.version = version.version;
  sample.scenario_digest = borrowString(scenario_digest);
  sample.effective_episode = version.effective_episode;
  sample.effective_time_s = version.effective_time_s;
  sample.horizon_s = schedule.horizon();
  sample.intervals = static_cast<std::uint32_t>(schedule.intervals());
  sample.sensor_count = static_cast<std::uint32_t>(schedule.sensorCount());
  borrowSequence(sample.rates_hz, rates);
  const std::string surrogate(wordOf(version.surrogate));
  sample.surrogate = borrowString(surrogate);
  sample.bracket_lower = version.bracket.info;
  sample.bracket_upper = version.bracket.cov;
  sample.command_id = version.command_id;
  sample.issued_wall_time_ns = wallNowNs();
  use(sample);
}

dds::WriteResult publishSchedule(dds::Writer<sensornet_Schedule>& writer,
                                 const std::string& run_id, const std::string& scenario_digest,
                                 const ScheduleVersion& version) {
  dds::WriteResult result = dds::WriteResult::TimedOut;
  withScheduleSample(run_id, scenario_digest, version,
                     [&](const sensornet_Schedule& s) { result = writer.write(s); });
  return result;
}

ScheduleVersion scheduleFromWire(const sensornet_Schedule& sample, const Scenario& scenario,
                                 const std::string& scenario_digest) {
  const std::string source = "DDS Schedule v" + std::to_string(sample.version);
  if (sample.version < 1) throw InputError(source, "version", "an integer >= 1");
  if (viewString(sample.scenario_digest) != scenario_digest) {
    throw InputError(source, "scenario_digest", "the run's scenario digest " + scenario_digest);
  }
  const auto n_intervals = static_cast<std::uint32_t>(scenario.intervals);
  const auto n_sensors = static_cast<std::uint32_t>(scenario.sensorCount());
  if (sample.intervals != n_intervals || sample.sensor_count != n_sensors ||
      sample.horizon_s != scenario.horizon_s) {
    throw InputError(source, "intervals/sensor_count/horizon_s",
                     "the scenario's N = " + std::to_string(n_intervals) +
                         ", M = " + std::to_string(n_sensors));
  }
  const auto rates = viewSequence(sample.rates_hz);
  if (rates.size() != static_cast<std::size_t>(n_intervals) * n_sensors) {
    throw InputError(source, "rates_hz", "N x M = " + std::to_string(n_intervals * n_sensors) +
                                             " values, got " + std::to_string(rates.size()));
  }
  if (!(std::isfinite(sample.effective_time_s) && sample.effective_time_s >= 0.0 &&
        sample.effective_time_s <= scenario.horizon_s)) {
    throw InputError(source, "effective_time_s", "a time in [0, T]");
  }
  Eigen::MatrixXd matrix(scenario.intervals, scenario.sensorCount());
  for (int k = 0; k < scenario.intervals; ++k) {
    for (int j = 0; j < scenario.sensorCount(); ++j) {
      const double rate = rates[static_cast<std::size_t>(k * scenario.sensorCount() + j)];
      if (!std::isfinite(rate) || rate < 0.0) {
        throw InputError(source, "rates_hz", "finite rates >= 0");
      }
      matrix(k, j) = rate;
    }
  }
  ScheduleVersion version;
  version.version = sample.version;
  version.effective_episode = sample.effective_episode;
  version.effective_time_s = sample.effective_time_s;
  version.schedule = RateSchedule(scenario.horizon_s, std::move(matrix));
  version.surrogate =
      parseWord<SurrogateKind>(viewString(sample.surrogate), source, "surrogate");
  version.bracket = {sample.bracket_lower, sample.bracket_upper};
  version.command_id = sample.command_id;
  return version;
}

std::optional<SensorState> sensorStateOf(sensornet_SensorState state) {
  using S = SensorState;
  switch (state) {
    case sensornet_SENSOR_STARTING: return S::Starting;
    case sensornet_SENSOR_READY: return S::Ready;
    case sensornet_SENSOR_RUNNING: return S::Running;
    case sensornet_SENSOR_EXCLUDED: return S::Excluded;
    case sensornet_SENSOR_STOPPED: return S::Stopped;
    case sensornet_SENSOR_FAILED: return S::Failed;
  }
  return std::nullopt;
}

sensornet_SensorState wireSensorState(SensorState state) {
  using S = SensorState;
  switch (state) {
    case S::Starting: return sensornet_SENSOR_STARTING;
    case S::Ready: return sensornet_SENSOR_READY;
    case S::Running: return sensornet_SENSOR_RUNNING;
    case S::Excluded: return sensornet_SENSOR_EXCLUDED;
    case S::Stopped: return sensornet_SENSOR_STOPPED;
    case S::Failed: return sensornet_SENSOR_FAILED;
  }
  return sensornet_SENSOR_FAILED;
}

sensornet_Report reportSample(const std::string& run_id, const EpisodeResult& e,
                              const RunSummary& s, std::vector<sensornet_SensorCounts>& counts) {
  counts.clear();
  for (std::size_t j = 0; j < e.sensors.size(); ++j) {
    const SensorTally& t = e.sensors[j];
    counts.push_back({static_cast<std::uint32_t>(j), t.received, t.expected, t.lost, t.late,
                      t.sent, t.dropped_by_network});
  }
  sensornet_Report r{};
  r.run_id = dds::borrowString(run_id);
  r.episode = e.episode;
  r.realized_cost = e.realized_cost;
  r.realtime_cost = e.realtime_cost;
  r.bracket_lower = e.bracket.info;
  r.bracket_upper = e.bracket.cov;
  r.delivered_bracket_lower = e.delivered_bracket.info;
  r.delivered_bracket_upper = e.delivered_bracket.cov;
  dds::borrowSequence(r.schedule_versions, e.versions);
  r.nees = e.nees;
  dds::borrowSequence(r.counts, counts);
  r.latency_median_s = s.latency_median_s;
  r.latency_p99_s = s.latency_p99_s;
  r.summary.episodes = s.episodes;
  r.summary.episodes_complete = s.episodes_complete;
  r.summary.realized_mean = s.mean;
  r.summary.realized_ci95_low = s.ci95_low;
  r.summary.realized_ci95_high = s.ci95_high;
  r.summary.realtime_mean = s.realtime_mean;
  r.summary.bracket_lower_mean = s.bracket_mean.info;
  r.summary.bracket_upper_mean = s.bracket_mean.cov;
  r.summary.meets_bracket = s.meets_bracket.value_or(false);
  r.summary.delivered_lower_mean = s.delivered_bracket_mean.info;
  r.summary.delivered_upper_mean = s.delivered_bracket_mean.cov;
  r.summary.meets_delivered_bracket = s.meets_delivered_bracket.value_or(false);
  r.summary.nees_mean = s.nees_mean;
  r.summary.sent = s.sent;
  r.summary.received = s.received;
  r.summary.lost = s.lost;
  r.summary.dropped_by_network = s.dropped_by_network;
  r.summary.latency_median_s = s.latency_median_s;
  r.summary.latency_p99_s = s.latency_p99_s;
  r.complete = e.complete;
  r.incomplete_reason = dds::borrowString(e.incomplete_reason);
  return r;
}

nlohmann::json episodeEntryOfReport(const sensornet_Report& r, int sensor_count) {
  if (r.complete && !std::isfinite(r.realized_cost)) {
    throw InputError("Report of episode " + std::to_string(r.episode), "realized_cost",
                     "a finite number in a complete episode's Report, got " +
                         std::to_string(r.realized_cost));
  }
  EpisodeResult e;
  e.episode = r.episode;
  e.realized_cost = r.realized_cost;
  e.realtime_cost = r.realtime_cost;
  e.received_realtime_cost = std::numeric_limits<double>::quiet_NaN();
  e.bracket = {r.bracket_lower, r.bracket_upper};
  e.delivered_bracket = {r.delivered_bracket_lower, r.delivered_bracket_upper};
  const auto versions = dds::viewSequence(r.schedule_versions);
  e.versions.assign(versions.begin(), versions.end());
  e.nees = r.nees;
  e.sensors.resize(static_cast<std::size_t>(std::max(sensor_count, 0)));
  std::vector<bool> counted(e.sensors.size(), false);
  for (const sensornet_SensorCounts& c : dds::viewSequence(r.counts)) {
    if (c.sensor_id >= e.sensors.size() || counted[c.sensor_id]) {
      throw InputError("Report of episode " + std::to_string(r.episode), "counts.sensor_id",
                       "each sensor of the scenario (0.." + std::to_string(sensor_count - 1) +
                           ") at most once, got " + std::to_string(c.sensor_id));
    }
    counted[c.sensor_id] = true;
    SensorTally& t = e.sensors[c.sensor_id];
    t.sent = c.sent;
    t.received = c.received;
    t.lost = c.lost;
    t.late = c.late;
    t.expected = c.expected;
    t.dropped_by_network = c.dropped_by_network;
    t.tallied = true;
  }
  e.complete = r.complete;
  e.incomplete_reason = std::string(dds::viewString(r.incomplete_reason));
  nlohmann::json entry = episodeEntry(e);
  entry["latency_median_s"] = r.latency_median_s;
  entry["latency_p99_s"] = r.latency_p99_s;
  return entry;
}

sensornet_EpisodeCommand episodeCommandOf(ControlKind kind) {
  switch (kind) {
    case ControlKind::EpisodeStart:
      return sensornet_EPISODE_START;
    case ControlKind::EpisodeStop:
      return sensornet_EPISODE_STOP;
    case ControlKind::SensorsFailed:
      return sensornet_EPISODE_SENSORS_FAILED;
    case ControlKind::RunShutdown:
      return sensornet_RUN_SHUTDOWN;
  }
  return sensornet_RUN_SHUTDOWN;
}

sensornet_EpisodeControl wireControl(const EpisodeControl& control, const std::string& run_id) {
  sensornet_EpisodeControl c{};
  c.run_id = borrowString(run_id);
  c.episode = control.episode;
  c.command = episodeCommandOf(control.kind);
  c.start_wall_time_ns = control.start_wall_ns;
  c.time_scale = control.time_scale;
  c.seed = control.seed;
  c.schedule_version = control.schedule_version;
  c.episodes_planned = control.episodes_planned;
  c.failed_at_s = control.failed_at_s;
  c.aborted = control.aborted;
  c.detail = borrowString(control.detail);
  borrowSequence(c.failed_sensors, control.failed_sensors);
  return c;
}

EpisodeControl controlOf(const sensornet_EpisodeControl& c) {
  EpisodeControl control;
  switch (c.command) {
    case sensornet_EPISODE_START:
      control.kind = ControlKind::EpisodeStart;
      break;
    case sensornet_EPISODE_STOP:
      control.kind = ControlKind::EpisodeStop;
      break;
    case sensornet_EPISODE_SENSORS_FAILED:
      control.kind = ControlKind::SensorsFailed;
      break;
    case sensornet_RUN_SHUTDOWN:
      control.kind = ControlKind::RunShutdown;
      break;
    default:
      throw InputError("DDS EpisodeControl of episode " + std::to_string(c.episode), "command",
                       "one of the IDL's EpisodeCommand values");
  }
  control.episode = c.episode;
  control.start_wall_ns = c.start_wall_time_ns;
  control.time_scale = c.time_scale;
  control.seed = c.seed;
  control.schedule_version = c.schedule_version;
  control.episodes_planned = c.episodes_planned;
  const auto failed = viewSequence(c.failed_sensors);
  control.failed_sensors.assign(failed.begin(), failed.end());
  control.failed_at_s = c.failed_at_s;
  control.aborted = c.aborted;
  control.detail = std::string(viewString(c.detail));
  return control;
}

}  // namespace sensornet::wire
