#include "sensornet/conform/conform_run.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <random>
#include <stdexcept>

#include "sensornet/core/input_error.hpp"
#include "sensornet/dds/domain.hpp"
#include "sensornet/io/command_line.hpp"
#include "sensornet/io/forwarded_options.hpp"
#include "sensornet/io/mcap.hpp"
#include "sensornet/io/scenario_file.hpp"
#include "sensornet/launcher/outside_roles.hpp"
#include "sensornet/launcher/process_group.hpp"
#include "sensornet/report/report_files.hpp"

namespace sensornet::conform {
namespace fs = std::filesystem;
using namespace std::chrono_literals;

bool ConformResult::allPass() const {
  return !rules.empty() &&
         std::all_of(rules.begin(), rules.end(), [](const RuleCheck& r) { return r.pass; });
}

std::vector<std::string> fillPlaceholders(const std::vector<std::string>& args,
                                          const std::map<std::string, std::string>& values,
                                          const std::string& source) {
  std::vector<std::string> filled;
  for (const std::string& arg : args) {
    std::string out;
    for (std::size_t i = 0; i < arg.size();) {
      const std::size_t open = arg.find('{', i);
      if (open == std::string::npos) {
        out += arg.substr(i);
        break;
      }
      const std::size_t close = arg.find('}', open);
      const std::string name =
          close == std::string::npos ? "" : arg.substr(open + 1, close - open - 1);
      const auto value = values.find(name);
      if (value == values.end()) {
        std::string known;
        for (const auto& [k, v] : values) known += (known.empty() ? "{" : ", {") + k + "}";
        throw InputError(source, arg, "placeholders among " + known);
      }
      out += arg.substr(i, open - i) + value->second;
      i = close + 1;
    }
    filled.push_back(out);
  }
  return filled;
}

namespace {

std::string roleName(ConformRole role, int sensor) {
  switch (role) {
    case ConformRole::Sensor:
      return "sensor " + std::to_string(sensor) + "'s";
    case ConformRole::FusionCenter:
      return "the fusion center's";
    case ConformRole::Scheduler:
      break;
  }
  return "a scheduler's (each command's first copy goes unanswered)";
}

std::string freshRunId() {
  std::random_device device;
  return fmt::format("conform-{:08x}", device());
}

}  // namespace

ConformResult conform(const ConformOptions& options,
                      const std::function<void(const std::string&)>& say) {
  const auto began = std::chrono::steady_clock::now();
  const Scenario scenario = loadScenarioFile(options.scenario.string());
  const bool sensor_role = options.role == ConformRole::Sensor;
  if (sensor_role && (options.sensor < 0 || options.sensor >= scenario.sensorCount())) {
    throw InputError("--sensor", std::to_string(options.sensor),
                     fmt::format("a sensor of {} (0 to {})", options.scenario.string(),
                                 scenario.sensorCount() - 1));
  }
  if (options.program.empty()) {
    throw InputError("sensornet conform", "PROGRAM", "the participant's command line");
  }
  ConformResult result;
  result.run_id = options.run_id.empty() ? freshRunId() : options.run_id;
  dds::validateRunId(result.run_id, "--run-id");
  result.dir = options.dir.empty() ? fs::temp_directory_path() / ("sensornet-" + result.run_id)
                                   : options.dir;
  const fs::path& dir = result.dir;
  fs::create_directories(dir);
  const int domain_id = static_cast<int>(dds::domainIdForRun(result.run_id));
  wire::RunOptions run;
  run.run_id = result.run_id;
  const fs::path config = launcher::outsideConfigFile(dir, run, false);
  const std::string sensor = std::to_string(options.sensor);
  std::map<std::string, std::string> values = {{"run_id", result.run_id},
                                               {"domain_id", std::to_string(domain_id)},
                                               {"config", config.string()}};
  std::vector<std::string> participant = {
      "/usr/bin/env", "CYCLONEDDS_URI=file://" + config.string(),
      "SENSORNET_RUN_ID=" + result.run_id, "SENSORNET_DOMAIN_ID=" + std::to_string(domain_id)};
  if (sensor_role) {
    values["sensor"] = sensor;
    values["dim"] =
        std::to_string(scenario.sensors[static_cast<std::size_t>(options.sensor)].H.rows());
    participant.push_back("SENSORNET_SENSOR=" + sensor);
  }
  const std::vector<std::string> program =
      fillPlaceholders(options.program, values, "the participant's command line");
  participant.insert(participant.end(), program.begin(), program.end());

  const fs::path recording = dir / "run.mcap";
  const fs::path report_path = dir / "report.json";
  // clang-format off
  std::vector<std::string> launch = {
      options.sensornet.string(), "launch", fs::absolute(options.scenario).string(),
      "--run-id", result.run_id,
      "--domain-id", std::to_string(domain_id),
      "--episodes", std::to_string(options.episodes),
      "--time-scale", formatNumber(options.time_scale),
      "--seed", std::to_string(options.seed),
      "--record", recording.string(),
      "--report", report_path.string(),
      "--log-dir", (dir / "logs").string(),
      "--timeout", std::to_string(options.timeout.count()),
      "--no-html"};
  // clang-format on
  if (sensor_role) {
    launch.insert(launch.end(), {"--external-sensors", sensor});
  } else if (options.role == ConformRole::FusionCenter) {
    launch.insert(launch.end(), {"--external-fusion-center", "--reference-fusion"});
  } else {
    launch.emplace_back(kDropFirstCommandCopyFlag);
  }
  launch.insert(launch.end(), options.launch_args.begin(), options.launch_args.end());

  launcher::ProcessGroup processes;
  processes.start({"launch", launch, dir / "launch.log"});
  processes.start({"participant", participant, dir / "participant.log"});
  say(fmt::format("conform: run {} on DDS domain {}, your program in {} role; its output: {}",
                  result.run_id, domain_id,
                  roleName(options.role, options.sensor),
                  (dir / "participant.log").string()));

  RunFacts facts;
  facts.measures_truth = options.measures_truth;
  const auto deadline = std::chrono::steady_clock::now() + options.timeout + 30s;
  std::optional<launcher::ChildExit> launched, left;
  while (!launched) {
    launched = processes.waitFor("launch", 1s);
    // A program that fails while the run goes on is told at once; one that leaves cleanly has
    // most likely seen the shutdown.
    for (const launcher::ChildExit& e : processes.reap()) {
      if (e.name == "launch") launched = e;
      if (e.name != "participant") continue;
      left = e;
      if (!e.succeeded()) {
        say("conform: your program " + e.describe() + " while the run goes on (see its output)");
      }
    }
    if (!launched && std::chrono::steady_clock::now() > deadline) {
      say("conform: the run did not end in time; stopping it");
      launched = launcher::ChildExit{"launch", 0, 1, 0};  // unless stop() tells how it ended
      for (const launcher::ChildExit& e : processes.stop({"launch"}, 20s)) launched = e;
    }
  }
  facts.launcher_exit = launched->exit_code;  // 128 + the signal when one ended it
  // The participant leaves by itself on RUN_SHUTDOWN; a few seconds for its acknowledgements.
  if (!left) left = processes.waitFor("participant", 5s);
  if (left) {
    if (left->signal == 0) facts.program_exit = left->exit_code;
    facts.program_end = (left->signal != 0 ? "was " : "") + left->describe();
  } else {
    processes.stop({"participant"}, 3s);
    facts.program_end = "was still running 5 s after the run ended: stopped";
  }

  const report::ReportFile file = report::readReport(report_path);
  if (file.ok()) facts.report = report::decodeRunRecord(file.report);
  if (!fs::exists(recording)) {
    throw std::runtime_error("the run left no recording to judge (" + recording.string() +
                             "); the launcher exited " + std::to_string(facts.launcher_exit) +
                             ", see " + (dir / "launch.log").string());
  }
  const McapReader mcap(recording);
  const RecordedRun recorded =
      readRecording(mcap, recording.string(),
                    sensor_role ? std::vector<int>{options.sensor} : std::vector<int>{});
  switch (options.role) {
    case ConformRole::Sensor:
      result.rules = checkSensor(recorded, options.sensor, facts);
      break;
    case ConformRole::FusionCenter:
      result.rules = checkFusionCenter(recorded, facts, options.tolerance);
      break;
    case ConformRole::Scheduler:
      result.rules = checkScheduler(recorded, facts);
      break;
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
  return result;
}

}  // namespace sensornet::conform
