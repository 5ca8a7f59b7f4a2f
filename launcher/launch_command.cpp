#include "launch_command.hpp"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "interrupts.hpp"
#include "process_group.hpp"
#include "progress_watcher.hpp"
#include "run_files.hpp"
#include "run_supervisor.hpp"
#include "sensornet/emulator/run_options.hpp"
#include "sensornet/io/scenario_file.hpp"

namespace sensornet::launcher {
namespace {

namespace fs = std::filesystem;
using std::chrono::milliseconds;
using std::chrono::seconds;

constexpr const char* kCoordinator = "coordinator";
constexpr const char* kFusionCenter = "fusion_center";
constexpr seconds kStopGrace{3};
// After the coordinator ends the run, the fusion center writes its report and exits; the
// sensor agents leave on the same RUN_SHUTDOWN.
constexpr seconds kFusionCenterExitLimit{15};
constexpr seconds kSensorAgentExitLimit{5};
constexpr std::size_t kLogLinesShown = 15;
constexpr int kExitInterrupted = 130;  // 128 + SIGINT, as shells report Ctrl-C

struct LaunchOptions {
  std::string scenario_path;
  int episodes = 20;
  double time_scale = 1.0;
  std::string report_path;
  int sensors_per_process = 1;
  std::string surrogate = "info";
  std::string schedule_path;
  emulator::RunOptions run;
  std::string log_dir;
  double timeout_s = 0.0;  // 0: no limit
  bool json = false;
};

// What one launch starts, decided before anything starts.
struct LaunchPlan {
  std::string run_id;
  fs::path log_dir;
  fs::path report_path;
  std::vector<ChildSpec> children;  // in start order: fusion center, sensor agents, coordinator
  std::vector<std::string> sensor_agents;
};

// The shortest text that reads back as `value` ("10", "0.1").
std::string formatNumber(double value) {
  char text[32];
  const auto result = std::to_chars(text, text + sizeof text, value);
  return std::string(text, result.ptr);
}

// The flags every child needs to join the run: the launcher's own, resolved.
std::vector<std::string> runFlags(const LaunchOptions& options, const dds::DomainConfig& domain) {
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

// "3" for a block of one sensor, "3-5" for sensors 3, 4 and 5.
std::string blockSpec(int first, int last) {
  return first == last ? std::to_string(first) : std::to_string(first) + "-" + std::to_string(last);
}

ChildSpec childSpec(const std::string& name, std::vector<std::string> argv,
                    const std::vector<std::string>& run_flags, const fs::path& log_dir) {
  argv.insert(argv.end(), run_flags.begin(), run_flags.end());
  return {name, std::move(argv), log_dir / (name + ".log")};
}

LaunchPlan planLaunch(const LaunchOptions& options, int sensor_count,
                      const EmulatorPrograms& programs, const dds::DomainConfig& domain) {
  LaunchPlan plan;
  plan.run_id = options.run.run_id;
  plan.log_dir =
      options.log_dir.empty() ? defaultLogDirectory(plan.run_id) : fs::absolute(options.log_dir);
  plan.report_path = options.report_path.empty() ? plan.log_dir / "report.json"
                                                 : fs::absolute(options.report_path);
  const std::vector<std::string> flags = runFlags(options, domain);

  plan.children.push_back(childSpec(kFusionCenter,
                                    {programs.fusion_center, "serve", "--report", plan.report_path},
                                    flags, plan.log_dir));
  const int per_process = options.sensors_per_process;
  for (int first = 0; first < sensor_count; first += per_process) {
    const std::string block = blockSpec(first, std::min(first + per_process, sensor_count) - 1);
    const std::string name = "sensor_agent-" + block;
    plan.children.push_back(
        childSpec(name, {programs.sensor_agent, "--sensors", block}, flags, plan.log_dir));
    plan.sensor_agents.push_back(name);
  }
  std::vector<std::string> coordinator = {programs.coordinator, "serve",
                                          "--scenario",         fs::absolute(options.scenario_path),
                                          "--surrogate",        options.surrogate,
                                          "--episodes",         std::to_string(options.episodes),
                                          "--time-scale",       formatNumber(options.time_scale)};
  if (!options.schedule_path.empty()) {
    coordinator.insert(coordinator.end(), {"--schedule", fs::absolute(options.schedule_path)});
  }
  plan.children.push_back(childSpec(kCoordinator, std::move(coordinator), flags, plan.log_dir));
  return plan;
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

// Watches the run to its end: the coordinator, then the fusion center (which writes the
// report), then the sensor agents. Sensor agents still running after their limit are stopped
// by the caller; that alone does not fail a run whose report is written.
void superviseRun(RunSupervisor& supervisor, const LaunchPlan& plan) {
  if (!supervisor.awaitExit(kCoordinator, RunSupervisor::kNoLimit)) return;
  if (!supervisor.awaitExit(kFusionCenter, kFusionCenterExitLimit)) {
    supervisor.fail({RunFailureKind::ChildFailed, kFusionCenter,
                     "did not exit within " + std::to_string(kFusionCenterExitLimit.count()) +
                         " s after the coordinator ended the run",
                     0});
    return;
  }
  const auto until = RunSupervisor::Clock::now() + kSensorAgentExitLimit;
  for (const std::string& name : plan.sensor_agents) {
    const auto left =
        std::max(milliseconds(0),
                 std::chrono::duration_cast<milliseconds>(until - RunSupervisor::Clock::now()));
    if (!supervisor.awaitExit(name, left) && supervisor.failure()) return;
  }
}

void reportFailure(const RunFailure& failure, const LaunchPlan& plan, const ProcessGroup& group,
                   const std::vector<std::string>& still_running) {
  std::string what = failure.reason;
  if (!failure.child.empty()) what = failure.child + " " + what;
  const char* verb = failure.kind == RunFailureKind::Interrupted ? "stopped" : "failed";
  std::fprintf(stderr, "sensornet: run %s %s: %s\n", plan.run_id.c_str(), verb, what.c_str());
  if (!still_running.empty()) {
    std::string names;
    for (const std::string& name : still_running) names += (names.empty() ? "" : ", ") + name;
    std::fprintf(stderr, "sensornet: stopped %s\n", names.c_str());
  }
  if (failure.kind == RunFailureKind::ChildFailed) {
    if (const auto log = group.logOf(failure.child)) {
      std::fprintf(stderr, "--- last lines of %s ---\n%s---\n", log->c_str(),
                   lastLines(*log, kLogLinesShown).c_str());
    }
  }
  std::error_code ignored;
  if (fs::exists(plan.report_path, ignored)) {
    std::fprintf(stderr, "sensornet: partial report in %s\n", plan.report_path.c_str());
  }
  std::fprintf(stderr, "sensornet: logs in %s\n", plan.log_dir.c_str());
}

// The fusion center's final report, or nullopt with what is wrong with it ("wrote no report at
// ...", completing "fusion_center ...").
std::optional<nlohmann::json> readReport(const fs::path& path, const std::string& run_id,
                                         std::string& problem) {
  std::ifstream in(path);
  if (!in) {
    problem = "wrote no report at " + path.string();
    return std::nullopt;
  }
  nlohmann::json report = nlohmann::json::parse(in, nullptr, false);
  if (!report.is_object() || !report.contains("summary")) {
    problem = "wrote " + path.string() + ", which is not a sensornet report";
    return std::nullopt;
  }
  if (report.value("run_id", std::string()) != run_id) {
    problem = "wrote a report of another run in " + path.string();
    return std::nullopt;
  }
  if (const std::string status = report.value("status", std::string("completed"));
      status != "completed") {
    problem = "reports the run as " + status + " in " + path.string();
    return std::nullopt;
  }
  return report;
}

// Received, expected and lost measurements: from the summary, else summed over the sensors.
nlohmann::json measurementCounts(const nlohmann::json& report) {
  const nlohmann::json& summary = report["summary"];
  if (summary.contains("received") && summary.contains("expected") && summary.contains("lost")) {
    return {{"received", summary["received"]},
            {"expected", summary["expected"]},
            {"lost", summary["lost"]}};
  }
  double expected = 0.0;
  std::uint64_t received = 0, lost = 0;
  for (const nlohmann::json& sensor : report.value("sensors", nlohmann::json::array())) {
    received += sensor.value("received", std::uint64_t{0});
    expected += sensor.value("expected", 0.0);
    lost += sensor.value("lost", std::uint64_t{0});
  }
  return {{"received", received}, {"expected", expected}, {"lost", lost}};
}

void printReport(const nlohmann::json& report, const fs::path& path) {
  const nlohmann::json& s = report["summary"];
  const nlohmann::json bracket = s.value("bracket", nlohmann::json::object());
  const nlohmann::json counts = measurementCounts(report);
  const nlohmann::json latency = report.value("latency_s", nlohmann::json::object());
  std::printf("run %s: %s, %d episode(s)\n", report.value("run_id", std::string()).c_str(),
              report.value("status", std::string("completed")).c_str(),
              report.value("episodes", s.value("episodes", 0)));
  std::printf("realized cost: %.6g \u00b1 %.3g (95%%) against the bracket [%.6g, %.6g]: %s\n",
              s.value("mean", 0.0), s.value("ci95", 0.0), bracket.value("info", 0.0),
              bracket.value("cov", 0.0),
              s.value("meets_bracket", false) ? "meets it" : "DOES NOT meet it");
  std::printf("mean NEES: %.4g\n", s.value("nees_mean", 0.0));
  std::printf("measurements: %llu received, %.1f expected, %llu lost\n",
              static_cast<unsigned long long>(counts["received"].get<std::uint64_t>()),
              counts["expected"].get<double>(),
              static_cast<unsigned long long>(counts["lost"].get<std::uint64_t>()));
  std::printf("latency publish-to-fusion: median %.3g ms, p99 %.3g ms\n",
              1e3 * latency.value("median", 0.0), 1e3 * latency.value("p99", 0.0));
  std::printf("report: %s\n", path.c_str());
}

void printReportJson(const nlohmann::json& report, const fs::path& path) {
  nlohmann::json line = report["summary"];
  line["run_id"] = report["run_id"];
  line["status"] = report.value("status", std::string("completed"));
  line["report"] = path.string();
  printJson(line);
}

int failRun(const RunFailure& failure, const LaunchPlan& plan, ProcessGroup& group, bool json) {
  const std::vector<std::string> still_running = group.runningNames();
  (void)group.stopAll(kStopGrace);
  reportFailure(failure, plan, group, still_running);
  if (json) {
    std::string reason =
        failure.child.empty() ? failure.reason : failure.child + " " + failure.reason;
    printJson({{"run_id", plan.run_id},
               {"status", "failed"},
               {"reason", reason},
               {"logs", plan.log_dir.string()}});
  }
  return failure.kind == RunFailureKind::Interrupted && failure.signal == SIGINT ? kExitInterrupted
                                                                                 : kExitFailure;
}

int runLaunch(LaunchOptions options) {
  // Bad input fails here, before anything starts.
  const Scenario scenario = loadScenarioFile(options.scenario_path);
  if (!options.schedule_path.empty()) (void)loadScheduleFile(options.schedule_path, scenario);
  if (options.run.run_id.empty()) options.run.run_id = generateRunId();
  const dds::DomainConfig domain = options.run.domainConfig();
  const EmulatorPrograms programs = findEmulatorPrograms();
  const LaunchPlan plan = planLaunch(options, scenario.sensorCount(), programs, domain);
  fs::create_directories(plan.log_dir);
  fs::create_directories(plan.report_path.parent_path());
  std::error_code ignored;
  fs::remove(plan.report_path, ignored);  // a stale report must not pass for this run's

  std::fprintf(stderr,
               "run id: %s; change it live with: sensornet replan --run-id %s --surrogate cov "
               "(or --exclude, --budget, --schedule); see it with: sensornet status\n",
               plan.run_id.c_str(), plan.run_id.c_str());
  const CurrentRunRecord record(plan.run_id, options.run.domain_id);
  installInterruptHandlers();
  ProgressWatcher progress(domain, options.episodes);
  ProcessGroup group;
  for (const ChildSpec& child : plan.children) {
    const pid_t pid = group.start(child);
    spdlog::info("started {} (pid {}), log {}", child.name, pid, child.log_path.string());
  }
  std::optional<RunSupervisor::Clock::time_point> deadline;
  if (options.timeout_s > 0.0) {
    deadline =
        RunSupervisor::Clock::now() + std::chrono::duration_cast<RunSupervisor::Clock::duration>(
                                          std::chrono::duration<double>(options.timeout_s));
  }
  RunSupervisor supervisor(group, progress, deadline);
  superviseRun(supervisor, plan);
  if (const auto& failure = supervisor.failure()) {
    return failRun(*failure, plan, group, options.json);
  }
  for (const ChildExit& lingering : group.stopAll(kStopGrace)) {
    spdlog::warn("{} had not left after the run ended; stopped it ({})", lingering.name,
                 lingering.describe());
  }
  std::string problem;
  const auto report = readReport(plan.report_path, plan.run_id, problem);
  if (!report) {
    return failRun({RunFailureKind::ChildFailed, kFusionCenter, problem, 0}, plan, group,
                   options.json);
  }
  if (options.json) {
    printReportJson(*report, plan.report_path);
  } else {
    printReport(*report, plan.report_path);
  }
  return kExitOk;
}

}  // namespace

Subcommand addLaunchCommand(CLI::App& app) {
  auto options = std::make_shared<LaunchOptions>();
  CLI::App* cmd = app.add_subcommand(
      "launch",
      "Run one emulation of SCENARIO on this host: the coordinator, the fusion center and the "
      "sensor agents as separate processes over Cyclone DDS (loopback only unless "
      "--cyclone-config says otherwise). Prints one line per episode, then the realized cost "
      "against the bracket. While it runs, change the schedule with `sensornet replan` and "
      "see the sensors with `sensornet status` (both find the run by itself). Ctrl-C stops "
      "every process. Example:\n  sensornet launch scenarios/default.yaml --episodes 20 "
      "--time-scale 10 --report report.json");
  cmd->add_option("scenario", options->scenario_path, "scenario file (YAML)")->required();
  cmd->add_option("--episodes", options->episodes, "episodes to run")
      ->check(CLI::Range(1, 1'000'000))
      ->capture_default_str();
  cmd->add_option("--time-scale", options->time_scale,
                  "emulated seconds per wall second (10: ten times faster than real time)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--report", options->report_path,
                  "where the fusion center writes the final report (JSON); default "
                  "<log-dir>/report.json");
  cmd->add_option("--sensors-per-process", options->sensors_per_process,
                  "sensors hosted by each sensor_agent process")
      ->check(CLI::Range(1, 1'000'000))
      ->capture_default_str();
  cmd->add_option("--surrogate", options->surrogate,
                  "how the coordinator plans the schedule: uniform, info (eq. 11) or cov (eq. 15)")
      ->check(CLI::IsMember({"uniform", "info", "cov"}))
      ->capture_default_str();
  cmd->add_option("--schedule", options->schedule_path,
                  "use this schedule file (JSON) instead of planning one");
  emulator::addRunOptions(*cmd, options->run, /*run_id_required=*/false);
  cmd->get_option("--run-id")
      ->description(
          "the run's id (default: run-<pid>-<4 random hex digits>); its DDS partition is "
          "sensornet/ID and its domain id a hash of ID");
  cmd->add_option("--log-dir", options->log_dir,
                  "where each process's log goes (default /tmp/sensornet-<uid>/<run id>/)");
  cmd->add_option("--timeout", options->timeout_s,
                  "stop everything and fail if the run is not over after this many seconds")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--json", options->json,
                "print one JSON line: the report's summary with \"run_id\" and \"report\"");
  return {cmd, [options] { return runLaunch(*options); }};
}

}  // namespace sensornet::launcher
