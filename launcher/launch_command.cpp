#include "launch_command.hpp"

#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "sensornet/launcher/failure_notices.hpp"
#include "sensornet/launcher/host_placement.hpp"
#include "interrupts.hpp"
#include "sensornet/io/output_file.hpp"
#include "sensornet/launcher/process_group.hpp"
#include "sensornet/launcher/progress_watcher.hpp"
#include "report_command.hpp"
#include "sensornet/launcher/run_files.hpp"
#include "sensornet/launcher/run_lock.hpp"
#include "sensornet/launcher/run_outcome.hpp"
#include "run_supervisor.hpp"
#include "runs_command.hpp"
#include "sensornet/core/arrival_mode.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/emulator/coordinator_core.hpp"
#include "sensornet/report/report_page.hpp"
#include "sensornet/emulator/stop_signal.hpp"
#include "sensornet/planning/planner.hpp"
#include "sensornet/dds/security.hpp"
#include "sensornet/launcher/hosts_file.hpp"
#include "sensornet/report/junit_report.hpp"
#include "sensornet/recording/run_recorder.hpp"
#include "sensornet/io/metrics_server.hpp"
#include "sensornet/wire/messages.hpp"
#include "sensornet/wire/run_options.hpp"
#include "sensornet/emulator/run_report.hpp"
#include "sensornet/emulator/sensor_ids.hpp"
#include "sensornet/io/output_path.hpp"
#include "sensornet/io/scenario_file.hpp"
#include "sensornet/io/forwarded_options.hpp"
#include "sensornet/io/utc_time.hpp"
#include "sensornet/io/word_option.hpp"
#include "sensornet/launcher/launch_plan.hpp"
#include "sensornet/launcher/outside_roles.hpp"

namespace sensornet::launcher {
namespace {

namespace fs = std::filesystem;
using std::chrono::milliseconds;
using std::chrono::seconds;

constexpr seconds kStopGrace{3};
// How long a new launch listens for a live run of its id before starting anything: discovery
// on loopback takes a few milliseconds; this is the price of every launch, so it stays short.
constexpr milliseconds kLiveRunProbe{500};
constexpr std::size_t kLogLinesShown = 15;

// The launch's options (launch_plan.hpp) and how its processes reach the run's DDS domain.
struct CommandOptions : LaunchOptions {
  wire::RunOptions run;
};

// --require as parseRequirements() takes it, so that an unknown criterion is refused before
// anything starts.
CLI::Validator requirementList() {
  return CLI::Validator(
      [](std::string& input) -> std::string {
        try {
          (void)sensornet::report::parseRequirements(input);
        } catch (const InputError& e) {
          return (e.field().empty() ? "" : e.field() + ": ") + "expected " + e.expected();
        }
        return {};
      },
      "CRITERIA");
}

// The flags every child needs to join the run: the launcher's own, resolved.
std::vector<std::string> runFlags(const CommandOptions& options, const dds::DomainConfig& domain) {
  std::vector<std::string> flags = {"--run-id", options.run.run_id};
  if (options.run.domain_id) {
    flags.insert(flags.end(), {"--domain-id", std::to_string(domain.domain_id)});
  }
  // Without --cyclone-config the children read SENSORNET_CYCLONE_CONFIG like the launcher did.
  if (!options.run.cyclone_config.empty()) {
    flags.insert(flags.end(), {"--cyclone-config", domain.cyclone_config});
  }
  return flags;
}

// What planLaunch needs of this host and the run's domain.
PlanContext planContext(const CommandOptions& options, const Scenario& scenario,
                        const EmulatorPrograms& programs, const dds::DomainConfig& domain,
                        const launcher::HostsFile* hosts) {
  PlanContext context{options.run.run_id,       programs,
                      runFlags(options, domain), defaultLogDirectory(options.run.run_id),
                      scenario.sensorCount(),   scenario.network.has_value(),
                      hosts,                    {}};
  if (!options.run.security_dir.empty()) {
    context.security_folder = [dir = options.run.security_dir](const dds::SecurityIdentity& id) {
      return dds::roleFolderOf(dir, id).string();
    };
  }
  return context;
}

// --hosts: every child runs through its host's prefix with its host's Cyclone configuration.
void placeOnHosts(LaunchPlan& plan, const launcher::HostsFile& hosts,
                  const HostPlacement& placement) {
  for (ChildSpec& child : plan.children) {
    if (child.name == kCoordinator) {
      placement.place(child, hosts.coordinatorHost(), dds::DiscoveryRole::Hub);
    } else if (child.name == kFusionCenter || child.name == kReferenceFusionCenter) {
      placement.place(child, hosts.fusionCenterHost(), dds::DiscoveryRole::Hub);
    } else {
      const launcher::Host& host = hosts.hostOfSensor(plan.sensors_of.at(child.name).front());
      placement.place(child, host, dds::DiscoveryRole::Leaf);
    }
  }
}

// --hosts: the launcher's Cyclone configuration in the log folder, for the tools that join the
// run from this machine (sensornet status --cyclone-config <log dir>/cyclone-launcher.xml).
void writeLauncherConfig(const LaunchPlan& plan, const dds::DomainConfig& domain) {
  const fs::path path = plan.log_dir / "cyclone-launcher.xml";
  std::ofstream out(path, std::ios::trunc);
  out << domain.cyclone_config << "\n";
  if (!out) spdlog::warn("cannot write {}", path.string());
}


// The report and the episode log beside it must be able to take the run's results.
void checkReportPaths(const LaunchPlan& plan) {
  const std::string option = plan.default_report ? "report" : "--report";
  checkOutputFile(plan.report_path, option);
  checkOutputFile(sensornet::report::episodeLogPath(plan.report_path), option + " (its episode log)");
  checkOutputFile(sensornet::report::faultLogPath(plan.report_path), option + " (its fault log)");
}

// The log folder: made if missing (private when it is the default one, in the scratch folder;
// else as every output folder is made, io/output_path.hpp).
void makeLogDirectory(const LaunchPlan& plan) {
  if (plan.default_log_dir) {
    ensurePrivateDirectory(userScratchDirectory());
    ensurePrivateDirectory(plan.log_dir);
    return;
  }
  makeFolders(plan.log_dir, "--log-dir");
}

// Starts the run's processes and says so: one line each, but past the first kListedAgents sensor
// agents one line for the rest (a 200-process run printed 200 lines before its first progress).
void startChildren(ProcessGroup& group, const LaunchPlan& plan) {
  constexpr int kListedAgents = 8;
  int agents = 0;
  std::vector<std::pair<std::string, pid_t>> unlisted;
  const auto sayUnlisted = [&] {
    if (unlisted.empty()) return;
    spdlog::info("started {} more sensor agents, {} (pid {}) to {} (pid {}), logs {}/<name>.log",
                 unlisted.size(), unlisted.front().first, unlisted.front().second,
                 unlisted.back().first, unlisted.back().second, plan.log_dir.string());
    unlisted.clear();
  };
  for (const ChildSpec& child : plan.children) {
    const pid_t pid = group.start(child);
    const bool agent = child.name.starts_with("sensor_agent");
    if (agent && ++agents > kListedAgents) {
      unlisted.emplace_back(child.name, pid);
      continue;
    }
    sayUnlisted();
    spdlog::info("started {} (pid {}), log {}", child.name, pid, child.log_path.string());
  }
  sayUnlisted();
}

// Claims the run id before anything starts: a second launch of a live run is refused here,
// before it creates, removes or truncates anything of that run's. Then makes the log folder,
// checks what goes in it and removes an earlier run's results. Returns the lock that keeps the
// run's log folder this launch's own. (A --report given by the user is checked before.)
// `id_is_new`: the launch made the run id up and only this host can be heard, so no live run
// can have it, and the probe (kLiveRunProbe of every launch) is skipped.
std::unique_ptr<RunLock> claimRun(const LaunchPlan& plan, const ProgressWatcher& progress,
                                  const dds::DomainConfig& domain, bool external_fusion_center,
                                  bool id_is_new) {
  if (!id_is_new && progress.seesLiveRun(kLiveRunProbe, !external_fusion_center)) {
    throw InputError("--run-id " + plan.run_id, "",
                     "a run id not in use on this host: run " + plan.run_id +
                         " is live (its coordinator or fusion center answers on DDS domain " +
                         std::to_string(domain.domain_id) + ", partition " + domain.partition +
                         ")");
  }
  makeLogDirectory(plan);
  auto lock = std::make_unique<RunLock>(plan.log_dir, plan.run_id);
  if (plan.default_report) checkReportPaths(plan);
  for (const ChildSpec& child : plan.children) checkOutputFile(child.log_path, "log");
  // Results of an earlier run of this id must not pass for this run's.
  removeRegularFile(plan.report_path);
  removeRegularFile(sensornet::report::episodeLogPath(plan.report_path));
  removeRegularFile(sensornet::report::faultLogPath(plan.report_path));
  removeRegularFile(plan.coordinator_state);
  if (!plan.reference_report.empty()) {
    removeRegularFile(plan.reference_report);
    removeRegularFile(sensornet::report::episodeLogPath(plan.reference_report));
    removeRegularFile(sensornet::report::faultLogPath(plan.reference_report));
  }
  return lock;
}

// Forgets the current-run record when the launch ends, however it ends.
class CurrentRunRecord {
 public:
  // A record that cannot be written only costs `replan` and `status` their default run.
  CurrentRunRecord(const std::string& run_id, std::optional<int> domain_id) : run_id_(run_id) {
    try {
      recordCurrentRun({run_id, domain_id, ::getpid()});
    } catch (const std::exception& e) {
      spdlog::warn("cannot record the current run in {}: {}", currentRunFile().string(), e.what());
    }
  }
  CurrentRunRecord(const CurrentRunRecord&) = delete;
  CurrentRunRecord& operator=(const CurrentRunRecord&) = delete;
  ~CurrentRunRecord() { forgetCurrentRun(run_id_); }

 private:
  std::string run_id_;
};

// What the supervisor core needs to know of this launch: the sensor agents and their sensors,
// the external sensors, the failure policy, the scenario's scripted crashes, the time limit.
SupervisorConfig supervisorConfig(const LaunchPlan& plan, const CommandOptions& options,
                                  const Scenario& scenario, const std::vector<int>& external) {
  SupervisorConfig config;
  for (const std::string& name : plan.sensor_agents) {
    config.sensor_agents.emplace_back(name, plan.sensors_of.at(name));
  }
  config.on_sensor_failure = options.on_sensor_failure;
  if (options.external_fusion_center) {
    config.report_writer = options.reference_fusion ? kReferenceFusionCenter : "";
  }
  for (const CrashFault& crash : scenario.faults) config.scripted_crash_sensors.push_back(crash.sensor);
  config.external_sensors = external;
  if (options.timeout_s > 0.0) {
    config.timeout = std::chrono::duration_cast<milliseconds>(
        std::chrono::duration<double>(options.timeout_s));
  }
  return config;
}

// What went wrong, on standard error: the cause, what was stopped, the failing child's log.
void explainFailure(const RunFailure& failure, const LaunchPlan& plan, const ProcessGroup& group,
                    const std::vector<std::string>& stopped) {
  std::string what = failure.reason;
  if (!failure.child.empty()) what = failure.child + " " + what;
  const char* verb = failure.kind == RunFailureKind::Interrupted ? "stopped" : "failed";
  std::fprintf(stderr, "sensornet: run %s %s: %s\n", plan.run_id.c_str(), verb, what.c_str());
  if (!stopped.empty()) {
    std::string names;
    for (const std::string& name : stopped) names += (names.empty() ? "" : ", ") + name;
    std::fprintf(stderr, "sensornet: stopped %s\n", names.c_str());
  }
  if (failure.kind == RunFailureKind::ChildFailed) {
    if (const auto log = group.logOf(failure.child)) {
      std::fprintf(stderr, "--- last lines of %s ---\n%s---\n", log->c_str(),
                   lastLines(*log, kLogLinesShown).c_str());
    }
  }
  std::fprintf(stderr, "sensornet: logs in %s\n", plan.log_dir.c_str());
}

// External sensors no participant spoke for: the cause of a coordinator that gave up waiting
// is named with them (on standard error and in its fault's detail), not left at "exited with
// status 1".
void nameSilentExternals(const std::vector<int>& external, bool external_fusion_center,
                         const ProgressWatcher& progress, std::vector<Fault>& faults) {
  std::vector<int> silent;
  for (const int j : external) {
    if (!progress.heardFrom(j)) silent.push_back(j);
  }
  std::vector<std::string> whys;
  if (!silent.empty()) {
    whys.push_back("no participant spoke for the external sensors " +
                   emulator::formatSensorIds(silent) +
                   " (--external-sensors): the coordinator waited for them up to --ready-timeout");
  }
  if (external_fusion_center && !progress.reportWriterSeen()) {
    whys.emplace_back(
        "no participant played the fusion center (--external-fusion-center): no writer of the "
        "run's Report topic came within --ready-timeout");
  }
  for (const std::string& why : whys) {
    std::fprintf(stderr, "sensornet: %s\n", why.c_str());
    for (Fault& f : faults) {
      if (f.process == kCoordinator && f.kind == emulator::FaultKind::ProcessFailed) {
        f.detail += "; " + why;
      }
    }
  }
}

// A child that failed by itself says why in its log's last error line (a full disk, a file it
// could not write): the fault names that cause, not only the exit status.
void nameFailureCauses(const ProcessGroup& group, std::vector<Fault>& faults) {
  for (Fault& f : faults) {
    if (f.kind != emulator::FaultKind::ProcessFailed) continue;
    const auto log = group.logOf(f.process);
    if (!log) continue;
    if (const auto cause = lastErrorLine(*log)) f.detail += ": " + *cause;
  }
}

// Every role's identity and one per sensor process of `plan`, each checked (security.hpp).
void checkSecurityFiles(const CommandOptions& options, const LaunchPlan& plan) {
  std::vector<std::string> blocks;
  for (const std::string& name : plan.sensor_agents) {
    blocks.push_back(emulator::formatSensorIds(plan.sensors_of.at(name)));
  }
  std::string make = "sensornet pki init " + options.run.security_dir + " --force --scenario " +
                     options.scenario_path;
  if (options.sensors_per_process != "auto") {
    make += " --sensors-per-process " + options.sensors_per_process;
  }
  if (!options.hosts_path.empty()) make += " --hosts " + options.hosts_path;
  dds::checkSecurityFolder(options.run.security_dir, blocks, make);
}

int runLaunch(CommandOptions options) {
  // First of all: a Ctrl-C in the first instants (or SIGINT inherited as ignored, as a shell's
  // background job has it) is the run's interruption, seen by the supervisor at its first look,
  // never a launcher killed with 130 and no report (issue 31, chaos seed 45).
  installInterruptHandlers();
  const auto launched = std::chrono::steady_clock::now();
  // Bad input fails here, before anything starts.
  const Scenario scenario = loadScenarioFile(options.scenario_path);
  if (!options.schedule_path.empty()) (void)loadScheduleFile(options.schedule_path, scenario);
  // A made-up id (run-<launcher pid>-<random>) cannot be live where only this host is heard
  // (the loopback configuration, no hosts file): a live run's launcher is alive, and pids on one
  // host are unique among the living.
  const bool made_up_id = options.run.run_id.empty();
  if (made_up_id) options.run.run_id = generateRunId();
  const bool loopback_only = options.run.chosenCycloneConfig().empty();
  dds::DomainConfig domain = options.run.domainConfig();
  std::optional<launcher::HostsFile> hosts;
  std::optional<HostPlacement> placement;
  if (!options.hosts_path.empty()) {
    hosts = launcher::loadHostsFile(options.hosts_path, scenario.sensorCount());
    placement.emplace(*hosts);
    domain.cyclone_config = placement->launcherConfigXml();
  }
  const EmulatorPrograms programs = findEmulatorPrograms();
  if (options.reference_fusion && !options.external_fusion_center) {
    throw InputError("--reference-fusion", "",
                     "--external-fusion-center as well (the reference fusion center runs beside "
                     "an external one)");
  }
  if (options.reference_fusion && !options.run.security_dir.empty()) {
    throw InputError("--reference-fusion", "",
                     "a run without --security: the reference publishes in partition "
                     "<partition>/reference, which no identity of pki init may write in");
  }
  if (options.network_aware == "yes" && !scenario.network) {
    throw InputError(options.scenario_path, "network",
                     "a network: section for --network-aware yes (the scenario has none)");
  }
  if (options.replan_every_s > 0.0 && options.surrogate != PlanSurrogate::Information &&
      options.surrogate != PlanSurrogate::Covariance) {
    throw InputError("--replan-every", "--surrogate",
                     "info or cov (the closed loop re-plans with the run's surrogate), got " +
                         std::string(wordOf(options.surrogate)));
  }
  const std::vector<int> external =
      externalSensors(options.external_sensors, scenario.sensorCount());
  LaunchPlan plan =
      planLaunch(options, planContext(options, scenario, programs, domain, hosts ? &*hosts : nullptr));
  // Every identity's files, so that a bad one is refused here, not when its process starts.
  if (!options.run.security_dir.empty()) checkSecurityFiles(options, plan);
  if (placement) placeOnHosts(plan, *hosts, *placement);
  if (!plan.default_report) {
    makeParentFolders(plan.report_path, "--report");
    checkReportPaths(plan);
  }
  if (!options.junit_path.empty()) {
    makeParentFolders(options.junit_path, "--junit");
    checkOutputFile(options.junit_path, "--junit");
  }
  if (!options.record_path.empty()) {
    makeParentFolders(options.record_path, "--record");
    checkOutputFile(options.record_path, "--record");
  }
  if (!options.metrics_address.empty()) {
    if (options.external_fusion_center) {
      throw InputError("--metrics", "",
                       "our fusion center, which serves them (not --external-fusion-center)");
    }
    (void)MetricsServer(options.metrics_address);  // bad or busy: refused now, one line
  }
  if (plan.default_log_dir) ensurePrivateDirectory(userScratchDirectory());
  ProgressWatcher progress(domain, options.episodes, scenario.horizon_s, scenario.sensorCount());
  const std::unique_ptr<RunLock> lock = claimRun(plan, progress, domain,
                                                 options.external_fusion_center,
                                                 made_up_id && loopback_only && !hosts);
  if (placement) writeLauncherConfig(plan, domain);
  // An external fusion center's Reports are the run's results: the launcher keeps them in the
  // episode log, as our fusion center would, and builds the report from it.
  if (options.external_fusion_center) {
    progress.recordReportsTo(sensornet::report::episodeLogPath(plan.report_path), scenario.sensorCount());
  }

  // The flags a tool on this host needs to reach the run (--hosts: the launcher's config).
  wire::RunOptions run = options.run;
  run.run_id = plan.run_id;
  const std::string reach =
      " " + shellLine(run.reachFlags(
                placement ? (plan.log_dir / "cyclone-launcher.xml").string() : std::string()));
  std::fprintf(stderr,
               "run id: %s; change it live with: sensornet replan%s --surrogate info (or "
               "--exclude, --include, --budget, --schedule); see it with: sensornet status%s\n",
               plan.run_id.c_str(), reach.c_str(), reach.c_str());
  const OutsideRoles outside{external, options.external_fusion_center, options.reference_fusion};
  if (outside.any()) {
    const OutsideReach where{static_cast<int>(domain.domain_id), domain.partition,
                             outsideConfigFile(plan.log_dir, options.run, placement.has_value()),
                             {"--run-id", plan.run_id, "--domain-id",
                              std::to_string(domain.domain_id)}};
    std::fputs(outsideRolesAnnouncement(outside, where).c_str(), stderr);
    progress.adviseAfter(kOutsideAdviceDelay, [&progress, outside, where, &scenario] {
      std::vector<int> silent;
      for (const int j : outside.sensors) {
        if (!progress.heardFrom(j)) silent.push_back(j);
      }
      return outsideRolesAdvice(where, scenario, silent,
                                outside.fusion_center && !progress.reportWriterSeen());
    });
  }
  const CurrentRunRecord record(plan.run_id, options.run.domain_id);
  try {
    writeLaunchRecord(plan.log_dir, {plan.run_id, fs::absolute(options.scenario_path),
                                  options.episodes, plan.report_path, ::getpid(), utcNow()});
  } catch (const std::exception& e) {
    spdlog::warn("cannot record the run in {}: {}", plan.log_dir.string(), e.what());
  }
  // Recording starts before any process: volatile samples written before it would be lost.
  std::unique_ptr<recording::RunRecorder> recorder;
  if (!options.record_path.empty()) {
    recorder = std::make_unique<recording::RunRecorder>(
        progress.participant(), plan.run_id, options.record_path,
        McapMap{{"seed", options.seed},
                {"scenario", fs::absolute(options.scenario_path).string()},
                {"episodes", std::to_string(options.episodes)},
                {"domain_id", std::to_string(domain.domain_id)},
                {"started_at", utcNow()}});
  }
  ProcessGroup group;
  startChildren(group, plan);
  FailureNotices notices(progress.participant(), plan.run_id);
  Supervisor core(supervisorConfig(plan, options, scenario, external),
                  std::chrono::steady_clock::now());
  superviseRun(core, {group, progress, notices, plan.children, plan.log_dir, external});
  if (const auto& failure = core.failure()) {
    explainFailure(*failure, plan, group, core.stoppedChildren());
  }
  // One line per way they ended: six sensor agents that never heard of the end are one fact.
  std::map<std::string, std::vector<std::string>> lingering;  // how it ended -> who
  for (const ChildExit& left : group.stopAll(kStopGrace)) {
    lingering[left.describe()].push_back(left.name);
  }
  for (const auto& [how, names] : lingering) {
    std::string who;
    for (const std::string& name : names) who += (who.empty() ? "" : ", ") + name;
    spdlog::warn("{} had not left after the run ended; stopped {} ({})", who,
                 names.size() == 1 ? "it" : "them", how);
  }
  std::vector<Fault> faults = core.faults();
  nameFailureCauses(group, faults);
  nameSilentExternals(external, options.external_fusion_center, progress, faults);
  // Every process has left: what the recorder still holds goes in now, so that a recording
  // that fell short (a full disk) is one of the run's faults. It is closed once the outcome is
  // known (its run-end metadata).
  bool recording_fell_short = false;
  if (recorder) {
    if (const recording::RecordingSummary& drained = recorder->drain(); !drained.error.empty()) {
      recording_fell_short = true;
      std::error_code unknown;
      const std::uintmax_t kept = fs::file_size(drained.path, unknown);
      Fault short_recording{
          emulator::FaultKind::RecordingIncomplete, kLauncherProcess, {}, {},
          "--record: the recording fell short: " + drained.error + "; " +
              drained.path.string() + " ends after the last whole record written" +
              (unknown ? std::string() : " (" + std::to_string(kept) + " bytes)")};
      short_recording.survived = true;  // the run went on; its costs are unchanged
      faults.push_back(std::move(short_recording));
    }
  }
  const RunEnd end{
      plan.run_id,
      plan.report_path,
      scenario.sensorCount(),
      options.episodes,
      std::move(faults),
      core.interrupted(),
      options.require.empty() ? std::vector<sensornet::report::Requirement>{}
                              : sensornet::report::parseRequirements(options.require),
      external,
      options.external_fusion_center,
      plan.reference_report,
      progress.reportsRefused(),
      scenario.stateDim(),
      plan.log_dir};
  const RunOutcome outcome = settleRun(end);
  if (outcome.written_to) {
    std::fprintf(stderr, "sensornet: warning: the report is at %s, not at its path: %s\n",
                 outcome.written_to->c_str(), outcome.write_problem->c_str());
  } else if (outcome.write_problem) {
    std::fprintf(stderr, "sensornet: error: %s\n", outcome.write_problem->c_str());
  }
  if (recorder) {  // a recording that fell short is a fault (above); one that cannot close, a warning
    const recording::RecordingSummary recorded =
        recorder->stop({{"status", std::string(wordOf(outcome.status))},
                        {"exit_code", std::to_string(outcome.exit_code)},
                        {"ended_at", utcNow()}});
    if (!recorded.error.empty() && !recording_fell_short) {  // else the fault said it
      std::fprintf(stderr, "sensornet: warning: --record: the recording could not be closed: %s\n",
                   recorded.error.c_str());
    }
    if (recorded.error.empty()) {
      std::fprintf(stderr, "sensornet: recorded %llu samples (%llu bytes) in %s\n",
                   static_cast<unsigned long long>(recorded.messages),
                   static_cast<unsigned long long>(recorded.bytes), recorded.path.c_str());
    }
  }
  if (!options.junit_path.empty()) {  // like the page: a warning, never an exit code
    const sensornet::report::JunitRun junit{
        plan.run_id, outcome.status, outcome.exit_code, outcome.report.faults, outcome.checks,
        std::chrono::duration<double>(std::chrono::steady_clock::now() - launched).count()};
    try {
      replaceFileAtomically(options.junit_path, sensornet::report::junitXml(junit));
    } catch (const std::exception& e) {
      std::fprintf(stderr, "sensornet: warning: --junit: %s\n", e.what());
    }
  }
  if (!options.no_html) {  // a page that cannot be written is a warning, never an exit code
    if (const auto problem =
            sensornet::report::writePageBeside(outcome.written_to.value_or(plan.report_path))) {
      std::fprintf(stderr, "sensornet: warning: %s\n", problem->c_str());
    }
  }
  if (options.json) {
    printOutcomeJson(outcome, plan.report_path);  // each says where the report went
  } else {
    printOutcome(outcome, plan.report_path);
  }
  return outcome.exit_code;
}

constexpr const char* kLaunchFooter =
    "Exit status (docs/ARCHITECTURE.md, \"Run outcome\"; the report's \"status\" says the same):\n"
    "  0  completed: every episode complete, every sent measurement fused, no process failed\n"
    "  3  degraded: every episode ran, but something was lost, rejected or re-planned because "
    "of a fault, or a process died and the run survived it (a sensor agent: the "
    "--on-sensor-failure policy; the fusion center or the coordinator: restarted with --resume); "
    "the report's \"faults\" say what\n"
    "  1  failed or interrupted: the run could not finish (a process failed beyond what the run "
    "survives, --on-sensor-failure stop, every sensor dead, --timeout, "
    "or Ctrl-C/SIGTERM/SIGHUP, which exit 1 too, not 130)\n"
    "  2  bad input, refused before any process starts: a bad option or file, a report path "
    "that is not a regular file in a writable folder, a run id already in use on this host, "
    "an unknown --require criterion\n"
    "  4  the run completed or was degraded, but a --require criterion failed (a failed run "
    "stays 1)\n"
    "Files: <log dir>/<process>.log, the report (--report) and its episode log beside it "
    "(report.json -> report.jsonl, one line per finished episode). The default log folder "
    "is /tmp/sensornet-<uid>/<run id>/ ($SENSORNET_SCRATCH_DIR replaces /tmp/sensornet-<uid>), "
    "private (0700) and refused if it is a symbolic link, another user's, or writable by others.";

}  // namespace

Subcommand addLaunchCommand(CLI::App& app) {
  auto options = std::make_shared<CommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "launch",
      "Run one emulation of SCENARIO on this host: the coordinator, the fusion center and the "
      "sensor agents as separate processes over Cyclone DDS (loopback only unless "
      "--cyclone-config says otherwise). Prints one line per episode, then the realized cost "
      "against the bracket. While it runs, change the schedule with `sensornet replan` and "
      "see the sensors with `sensornet status` (both find the run by itself). Ctrl-C stops "
      "every process. Example:\n  sensornet launch scenarios/default.yaml --episodes 20 "
      "--time-scale 10 --report report.json");
  cmd->footer(kLaunchFooter);
  cmd->add_option("scenario", options->scenario_path, "scenario file (YAML)")->required();
  addEpisodesOption(*cmd, options->episodes);
  addTimeScaleOption(*cmd, options->time_scale);
  addSeedOption(*cmd, options->seed,
                " (the coordinator's --seed); the same seed, scenario and schedule give the same "
                "realized costs");
  cmd->add_option("--report", options->report_path,
                  "where the fusion center writes the final report (JSON): a regular file or a "
                  "new one (missing folders are made); default <log-dir>/report.json");
  cmd->add_option("--sensors-per-process", options->sensors_per_process,
                  "sensors hosted by each sensor_agent process; auto: one each up to " +
                      std::to_string(kAutoSensorProcesses) +
                      " processes, else the fewest equal blocks that stay within that many")
      ->check(sensorsPerProcessValue())
      ->capture_default_str();
  addSurrogateOption(*cmd, options->surrogate,
                     ". Default cov: its realized cost beat uniform and info on the paper's "
                     "sweeps (bench/README.md)");
  addScheduleOption(*cmd, options->schedule_path);
  wire::addRunOptions(*cmd, options->run, /*run_id_required=*/false);
  options->run.security_identity = dds::SecurityRole::Launcher;
  cmd->add_option("--hosts", options->hosts_path,
                  "run across several hosts: a YAML file naming each host's address, the "
                  "command prefix that runs a program there (ip netns exec NS, ssh -tt "
                  "user@host) and what it runs (coordinator, fusion_center, sensors); the "
                  "launcher stays here and generates every process's Cyclone configuration "
                  "(README, \"Many hosts\")")
      ->excludes("--cyclone-config");
  cmd->get_option("--run-id")
      ->description(
          "the run's id (default: run-<pid>-<4 random hex digits>); its DDS partition is "
          "sensornet/ID and its domain id a hash of ID. A launch whose id is in use on this "
          "host (a live run, or a launch holding its log folder) is refused with exit 2");
  cmd->add_option("--log-dir", options->log_dir,
                  "where each process's log goes, made if missing (default "
                  "/tmp/sensornet-<uid>/<run id>/)");
  addReadyTimeoutOption(*cmd, options->ready_timeout_s,
                        "; it waits for your sensors of --external-sensors too");
  addReplanEveryOption(*cmd, options->replan_every_s,
                       ". Offline: fusion_center evaluate --replan-every");
  addSwitchMarginOption(*cmd, options->switch_margin_s,
                        ". Default: the coordinator's, " +
                            formatNumber(emulator::CoordinatorConfig{}.switch_margin_s));
  addDropFirstCommandCopyOption(*cmd, options->drop_first_command_copy);
  cmd->add_option("--timeout", options->timeout_s,
                  "stop everything and fail if the run is not over after this many seconds "
                  "(0: no limit)")
      ->check(nonNegativeNumber(kMaxWallSeconds));
  addOnSensorFailureOption(*cmd, options->on_sensor_failure,
                           ". A sensor agent dies when it is killed, crashes, or by a scripted "
                           "crash of the scenario's faults:");
  wordOption(cmd->add_option(
                 std::string(kNetworkAwareFlag), options->network_aware,
                 "plan for the rates the scenario's emulated network delivers (loss thins them, "
                 "outages zero them): yes, no, or auto = yes when the scenario has a network: "
                 "section"),
             {"auto", "yes", "no"});
  addArrivalsOption(*cmd, options->arrivals,
                    ". Under timetable the bracket [info, cov] bounds the Poisson mean of the "
                    "schedule, not the run's cost");
  cmd->add_option("--external-sensors", options->external_sensors,
                  "sensors (ids as sensor_agent --sensors takes them: 2,5 or 0-2) that a "
                  "participant of your own speaks for: no agent is started for them, and the run "
                  "waits for their SensorStatus READY as for its own agents. It writes "
                  "Measurement, EpisodeTally and SensorStatus in a partition that names them, "
                  "sensornet/<run id>/sensors/<ids> (docs/wire-protocol.md, \"Sensor\")");
  cmd->add_flag("--external-fusion-center", options->external_fusion_center,
                "start no fusion center: a participant of your own fuses the run. It reads the "
                "run's topics, writes a Report per episode (the coordinator paces the episodes on "
                "them) and FusionState (docs/wire-protocol.md, \"Fusion center\"); the launcher "
                "builds the report from its Reports (report.jsonl beside it), with "
                "\"external\": {\"fusion_center\": true}");
  cmd->add_flag("--reference-fusion", options->reference_fusion,
                "with --external-fusion-center: also run ours on the same measurements as the "
                "reference (writing in <partition>/reference, log dir reference-report.json); "
                "the report adds per episode its realized cost beside the external one and their "
                "relative difference, and the criterion fusion-agreement<=X of --require checks "
                "the largest");
  cmd->add_option("--record", options->record_path,
                  "record every sample of every topic of the run, as this process received it, "
                  "in an MCAP file (message encoding cdr, schemas omgidl from idl/sensornet.idl; "
                  "readable by standard MCAP tools; see it with `sensornet replay FILE --info`); "
                  "the file is complete however the run ends, Ctrl-C included");
  addMetricsOption(*cmd, options->metrics_address,
                   ". Served: per sensor sent/received/lost/dropped/late, rejections, episodes, the "
                   "running mean cost and its interval, the latest schedule's version, bracket "
                   "and rates, latency as a histogram, faults by kind");
  cmd->add_option("--junit", options->junit_path,
                  "also write the run as JUnit XML for CI: a test case \"run\" that passes only "
                  "when the run completed (its message: status, exit code, faults by kind) and "
                  "one per --require criterion with the value measured");
  cmd->add_option("--require", options->require,
                  "make the run a CI gate: comma-separated criteria checked against the report "
                  "after the run, each printed as pass or FAIL with the value measured; any "
                  "failure exits 4. Example: --require "
                  "meets-bracket,no-loss,latency-p99<=5ms,episodes-complete. A criterion is a "
                  "property, or a quantity with <=, <, >=, > or = and a limit (durations in us, "
                  "ms or s). Known:\n" +
                      sensornet::report::requirementsHelp())
      ->check(requirementList());
  cmd->add_flag("--no-html", options->no_html,
                "do not write the report page (report.json -> report.html beside it; see "
                "`sensornet report`)");
  cmd->add_flag("--json", options->json,
                "print one JSON line at the end: the report's summary with \"run_id\", "
                "\"status\", \"faults\", \"report\" and \"exit_code\"");
  return {cmd, [options] { return runLaunch(*options); }};
}

}  // namespace sensornet::launcher
