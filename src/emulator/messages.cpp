#include "sensornet/emulator/messages.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <vector>

#include "sensornet/core/arrival_mode.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/dds/wire.hpp"
#include "sensornet/io/scenario_file.hpp"

namespace sensornet::emulator {
namespace {

using dds::borrowSequence;
using dds::borrowString;
using dds::viewSequence;
using dds::viewString;

}  // namespace

std::int64_t wallNowNs() {
  timespec now{};
  ::clock_gettime(CLOCK_REALTIME, &now);
  return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

std::string digestOf(std::string_view text) {
  std::uint64_t hash = 0xcbf29ce484222325ULL;
  for (const char c : text) {
    hash ^= static_cast<unsigned char>(c);
    hash *= 0x100000001b3ULL;
  }
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(hash));
  return hex;
}

dds::WriteResult publishScenario(dds::Writer<sensornet_Scenario>& writer,
                                 const std::string& run_id, const RunScenario& scenario) {
  sensornet_Scenario sample{};
  sample.run_id = borrowString(run_id);
  sample.digest = borrowString(scenario.digest);
  sample.yaml = borrowString(scenario.yaml);
  sample.horizon_s = scenario.scenario.horizon_s;
  sample.intervals = static_cast<std::uint32_t>(scenario.scenario.intervals);
  sample.sensor_count = static_cast<std::uint32_t>(scenario.scenario.sensorCount());
  sample.state_dim = static_cast<std::uint32_t>(scenario.scenario.stateDim());
  sample.seed = scenario.seed;
  const std::string arrivals(arrivalModeName(scenario.scenario.arrivals));
  sample.arrivals = borrowString(arrivals);
  return writer.write(sample);
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
  result.scenario.arrivals = arrivals.empty() ? ArrivalMode::Poisson
                                              : parseArrivalMode(arrivals, source, "arrivals");
  return result;
}

dds::WriteResult publishSchedule(dds::Writer<sensornet_Schedule>& writer,
                                 const std::string& run_id, const std::string& scenario_digest,
                                 const ScheduleVersion& version) {
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
  sample.surrogate = borrowString(version.surrogate);
  sample.bracket_lower = version.bracket.info;
  sample.bracket_upper = version.bracket.cov;
  sample.command_id = version.command_id;
  sample.issued_wall_time_ns = wallNowNs();
  return writer.write(sample);
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
  version.surrogate = std::string(viewString(sample.surrogate));
  version.bracket = {sample.bracket_lower, sample.bracket_upper};
  version.command_id = sample.command_id;
  return version;
}

std::string sensorStateName(sensornet_SensorState state) {
  switch (state) {
    case sensornet_SENSOR_STARTING:
      return "starting";
    case sensornet_SENSOR_READY:
      return "ready";
    case sensornet_SENSOR_RUNNING:
      return "running";
    case sensornet_SENSOR_EXCLUDED:
      return "excluded";
    case sensornet_SENSOR_STOPPED:
      return "stopped";
    case sensornet_SENSOR_FAILED:
      return "failed";
  }
  return "unknown";
}

}  // namespace sensornet::emulator
