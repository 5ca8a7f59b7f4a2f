#pragma once
// What `sensornet launch` starts, decided before anything starts: the fusion center (or, beside
// an external one with --reference-fusion, the reference fusion center), one sensor agent per
// block of sensors (--sensors-per-process, --hosts, minus --external-sensors) and the
// coordinator, in that order, each with its argv, log file and death signal; where the report,
// the coordinator's journal and the logs go. Pure: the caller resolves what needs the system or
// DDS (the run's flags of its domain, the security folder of each identity, the programs' paths,
// the default log folder) and starts the children (process_group.hpp).
//
//   LaunchOptions options;                       // as the user gave them, checked
//   const LaunchPlan plan = planLaunch(options, {.run_id = "run-1", .programs = programs,
//                                                .run_flags = {"--run-id", "run-1"},
//                                                .default_log_dir = "/tmp/sensornet-1000/run-1",
//                                                .sensor_count = 4});
//   plan.children[0].argv;   // {".../fusion_center", "serve", "--report", ..., "--run-id", ...}
//
// The options forwarded to the coordinator are named as io/forwarded_options.hpp declares them.

#include <csignal>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "sensornet/core/surrogate_kind.hpp"
#include "sensornet/dds/security.hpp"  // SecurityIdentity: header-only names, no DDS
#include "sensornet/launcher/hosts_file.hpp"
#include "sensornet/emulator/vocabulary.hpp"

namespace sensornet::launcher {

// The options of `sensornet launch` (the command line declares them, launcher/launch_command).
struct LaunchOptions {
  std::string scenario_path;
  int episodes = 20;
  double time_scale = 1.0;
  std::string seed = "1";  // checked by seedNumber(); passed on as written
  std::string report_path;
  std::string sensors_per_process = "auto";  // or a count: see sensorsPerProcess()
  PlanSurrogate surrogate = PlanSurrogate::Covariance;
  std::string schedule_path;
  std::string log_dir;
  double timeout_s = 0.0;  // 0: no limit
  bool json = false;
  bool no_html = false;  // no report page (report.html) beside the report
  emulator::FailurePolicy on_sensor_failure = emulator::FailurePolicy::Replan;
  std::string network_aware = "auto";  // auto: when the scenario has a network: section
  std::string arrivals;  // poisson or timetable; empty: the scenario's `arrivals:`
  std::string require;  // --require criteria (run_requirements.hpp), checked after the run
  std::string junit_path;  // --junit: the run and each criterion as JUnit test cases
  std::string record_path;  // --record: every sample of the run, as received, in an MCAP file
  std::string metrics_address;  // --metrics: our fusion center serves /metrics (Prometheus) here
  std::string external_sensors;  // --external-sensors: sensors a participant of the user's speaks for
  bool external_fusion_center = false;  // --external-fusion-center: a participant of the user's fuses
  bool reference_fusion = false;  // --reference-fusion: ours beside it, on the same measurements
  double ready_timeout_s = 30.0;  // --ready-timeout, passed to the coordinator
  double replan_every_s = 0.0;    // --replan-every, passed to the coordinator (0: open loop)
  std::optional<double> switch_margin_s;  // --switch-margin, passed to the coordinator
  bool drop_first_command_copy = false;   // --drop-first-command-copy, passed to the coordinator
  std::string hosts_path;  // --hosts: run across the hosts of this file (hosts_file.hpp)
};

// One process of the run, as ProcessGroup (process_group.hpp) starts it.
struct ChildSpec {
  std::string name;                // e.g. "coordinator", "sensor_agent-0-2"
  std::vector<std::string> argv;   // argv[0] is the program's path
  std::filesystem::path log_path;  // standard output and error, truncated at start
  // What the child gets when the launcher dies (PR_SET_PDEATHSIG): SIGKILL, so that nothing of
  // the run outlives the launcher; the fusion center gets emulator::kLauncherDeathSignal, on which it
  // writes the report with the launcher's death as its cause.
  int parent_death_signal = SIGKILL;
};

// The three programs a launch starts.
struct EmulatorPrograms {
  std::filesystem::path coordinator;
  std::filesystem::path fusion_center;
  std::filesystem::path sensor_agent;
};

// What planLaunch needs of the world, resolved by the caller.
struct PlanContext {
  std::string run_id;
  EmulatorPrograms programs;
  // What every child needs to join the run: --run-id, and --domain-id, --cyclone-config as given.
  std::vector<std::string> run_flags;
  std::filesystem::path default_log_dir;  // <scratch>/<run id>, for a launch without --log-dir
  int sensor_count = 0;
  bool scenario_has_network = false;
  const launcher::HostsFile* hosts = nullptr;  // --hosts; nullptr: this host
  // A secured run (--security): the folder a process of this identity receives; empty: none.
  std::function<std::string(const dds::SecurityIdentity&)> security_folder;
};

struct LaunchPlan {
  std::string run_id;
  std::filesystem::path log_dir;
  bool default_log_dir = false;  // in the scratch folder, which must be private
  std::filesystem::path report_path;
  bool default_report = false;      // in the log folder
  std::vector<ChildSpec> children;  // in start order: fusion center, sensor agents, coordinator
  std::vector<std::string> sensor_agents;
  std::map<std::string, std::vector<int>> sensors_of;  // sensor agent -> the sensors it hosts
  std::filesystem::path coordinator_state;  // the coordinator's journal, what a restarted one resumes from
  std::filesystem::path reference_report;   // --reference-fusion: the reference fusion center's report
};

// Throws InputError (naming the option) for --external-sensors that are not sensors of the
// scenario.
[[nodiscard]] LaunchPlan planLaunch(const LaunchOptions& options, const PlanContext& context);

// --external-sensors as sensor ids of the scenario (sorted); InputError for anything else.
[[nodiscard]] std::vector<int> externalSensors(const std::string& given, int sensor_count);

// The coordinator's --network-aware: --network-aware yes, or auto when the scenario has a
// network: section.
[[nodiscard]] bool networkAware(const std::string& given, bool scenario_has_network);

// --sensors-per-process auto: one sensor per process up to this many sensor processes, else
// the fewest equal blocks that stay within it. Start-up and the idle load grow with the number
// of processes, not of sensors; measured on the 2-core machine (bench/README.md, "Start-up at
// scale"), 60 one-sensor processes are all ready in about 3 s, 100 in about 10 s.
inline constexpr int kAutoSensorProcesses = 50;
inline constexpr int kMaxSensorsPerProcess = 1'000'000;
// The sensors of one sensor_agent process for --sensors-per-process `given` ("auto" or a whole
// number, checked already): the count given, or for "auto" one each up to kAutoSensorProcesses
// processes, else ceil(M / kAutoSensorProcesses).
[[nodiscard]] int sensorsPerProcess(const std::string& given, int sensor_count);
// The sensors of each sensor_agent process, `per_process` at most each: consecutive blocks of
// 0..sensor_count-1 on one host; on several hosts, blocks of each host's sensors in file order.
[[nodiscard]] std::vector<std::vector<int>> sensorBlocks(const launcher::HostsFile* hosts,
                                                         int sensor_count, int per_process);

}  // namespace sensornet::launcher
