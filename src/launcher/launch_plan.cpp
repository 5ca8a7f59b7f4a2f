#include "sensornet/launcher/launch_plan.hpp"

#include <algorithm>

#include "sensornet/core/input_error.hpp"
#include "sensornet/emulator/sensor_ids.hpp"
#include "sensornet/emulator/stop_signal.hpp"
#include "sensornet/io/command_line.hpp"
#include "sensornet/io/forwarded_options.hpp"
#include "sensornet/launcher/supervisor.hpp"

namespace sensornet::launcher {
namespace {

namespace fs = std::filesystem;
using dds::SecurityRole;

// The run's flags and, in a secured run, `--security` with the folder of `identity` alone: a
// process receives its own identity, key and permissions (and the CA's certificate and the
// governance), nothing of another role and never the CA's key (docs/ARCHITECTURE.md, README
// "DDS Security").
ChildSpec childSpec(const std::string& name, std::vector<std::string> argv,
                    const PlanContext& context, const dds::SecurityIdentity& identity,
                    const fs::path& log_dir) {
  argv.insert(argv.end(), context.run_flags.begin(), context.run_flags.end());
  if (context.security_folder) argv.insert(argv.end(), {"--security", context.security_folder(identity)});
  return {name, std::move(argv), log_dir / (name + ".log")};
}

void add(std::vector<std::string>& argv, std::string_view flag, std::string value) {
  argv.emplace_back(flag);
  argv.push_back(std::move(value));
}

// The coordinator's argv before the run's flags: the scenario, then every option the launcher
// forwards to it (io/forwarded_options.hpp), then its journal.
std::vector<std::string> coordinatorArgv(const LaunchOptions& options, const PlanContext& context,
                                         const fs::path& state) {
  std::vector<std::string> argv = {context.programs.coordinator, "serve", "--scenario",
                                   fs::absolute(options.scenario_path)};
  add(argv, kSurrogateFlag, std::string(wordOf(options.surrogate)));
  add(argv, kEpisodesFlag, std::to_string(options.episodes));
  add(argv, kTimeScaleFlag, formatNumber(options.time_scale));
  add(argv, kSeedFlag, options.seed);
  if (!options.schedule_path.empty()) add(argv, kScheduleFlag, fs::absolute(options.schedule_path));
  add(argv, kOnSensorFailureFlag, std::string(wordOf(options.on_sensor_failure)));
  argv.insert(argv.end(), {"--state", state});
  if (networkAware(options.network_aware, context.scenario_has_network)) {
    argv.emplace_back(kNetworkAwareFlag);
  }
  if (!options.arrivals.empty()) add(argv, kArrivalsFlag, options.arrivals);
  add(argv, kReadyTimeoutFlag, formatNumber(options.ready_timeout_s));
  if (options.replan_every_s > 0.0) add(argv, kReplanEveryFlag, formatNumber(options.replan_every_s));
  if (options.switch_margin_s) add(argv, kSwitchMarginFlag, formatNumber(*options.switch_margin_s));
  if (options.drop_first_command_copy) argv.emplace_back(kDropFirstCommandCopyFlag);
  return argv;
}

}  // namespace

bool networkAware(const std::string& given, bool scenario_has_network) {
  return given == "yes" || (given == "auto" && scenario_has_network);
}

std::vector<int> externalSensors(const std::string& given, int sensor_count) {
  if (given.empty()) return {};
  std::vector<int> ids = emulator::parseSensorIds(given, "--external-sensors");
  if (ids.back() >= sensor_count) {
    throw InputError("--external-sensors", "sensors",
                     "sensor ids of the scenario (0 to " + std::to_string(sensor_count - 1) +
                         "), got " + std::to_string(ids.back()));
  }
  return ids;
}

LaunchPlan planLaunch(const LaunchOptions& options, const PlanContext& context) {
  const int sensor_count = context.sensor_count;
  LaunchPlan plan;
  plan.run_id = context.run_id;
  plan.default_log_dir = options.log_dir.empty();
  plan.log_dir = plan.default_log_dir ? context.default_log_dir : fs::absolute(options.log_dir);
  plan.default_report = options.report_path.empty();
  plan.report_path =
      plan.default_report ? plan.log_dir / "report.json" : fs::absolute(options.report_path);

  if (!options.external_fusion_center) {
    // A report its disk refuses (full) goes beside the logs (report_files.hpp).
    std::vector<std::string> serve = {context.programs.fusion_center, "serve", "--report",
                                      plan.report_path.string(), "--report-fallback",
                                      plan.log_dir.string()};
    if (!options.metrics_address.empty()) add(serve, kMetricsFlag, options.metrics_address);
    plan.children.push_back(
        childSpec(kFusionCenter, serve, context, SecurityRole::FusionCenter, plan.log_dir));
    plan.children.back().parent_death_signal = emulator::kLauncherDeathSignal;  // it writes the report
  } else if (options.reference_fusion) {
    plan.reference_report = plan.log_dir / "reference-report.json";
    plan.children.push_back(childSpec(
        kReferenceFusionCenter,
        {context.programs.fusion_center, "serve", "--reference", "--report", plan.reference_report},
        context, SecurityRole::FusionCenter, plan.log_dir));
    plan.children.back().parent_death_signal = emulator::kLauncherDeathSignal;
  }
  const int per_process = sensorsPerProcess(options.sensors_per_process, sensor_count);
  // External sensors get no agent: a participant of the user's speaks for them.
  const std::vector<int> external = externalSensors(options.external_sensors, sensor_count);
  for (std::vector<int> sensors : sensorBlocks(context.hosts, sensor_count, per_process)) {
    std::erase_if(sensors,
                  [&](int j) { return std::binary_search(external.begin(), external.end(), j); });
    if (sensors.empty()) continue;
    const std::string block = emulator::formatSensorIds(sensors);
    const std::string name = "sensor_agent-" + block;
    plan.children.push_back(childSpec(name, {context.programs.sensor_agent, "--sensors", block},
                                      context, {SecurityRole::Sensor, block}, plan.log_dir));
    plan.sensor_agents.push_back(name);
    plan.sensors_of[name] = std::move(sensors);
  }
  plan.coordinator_state = plan.log_dir / "coordinator-state.json";
  plan.children.push_back(childSpec(kCoordinator,
                                    coordinatorArgv(options, context, plan.coordinator_state),
                                    context, SecurityRole::Coordinator, plan.log_dir));
  return plan;
}

int sensorsPerProcess(const std::string& given, int sensor_count) {
  if (given != "auto") return std::stoi(given);  // checked by the option's validator
  return std::max(1, (sensor_count + kAutoSensorProcesses - 1) / kAutoSensorProcesses);
}

std::vector<std::vector<int>> sensorBlocks(const launcher::HostsFile* hosts, int sensor_count,
                                           int per_process) {
  std::vector<std::vector<int>> groups;
  if (hosts == nullptr) {
    groups.emplace_back();
    for (int j = 0; j < sensor_count; ++j) groups.back().push_back(j);
  } else {
    for (const launcher::Host& host : hosts->hosts) groups.push_back(host.sensors);
  }
  std::vector<std::vector<int>> blocks;
  const auto size = static_cast<std::size_t>(std::max(1, per_process));
  for (const std::vector<int>& group : groups) {
    for (std::size_t first = 0; first < group.size(); first += size) {
      const auto last = std::min(first + size, group.size());
      blocks.emplace_back(group.begin() + static_cast<std::ptrdiff_t>(first),
                          group.begin() + static_cast<std::ptrdiff_t>(last));
    }
  }
  return blocks;
}

}  // namespace sensornet::launcher
