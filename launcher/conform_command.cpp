#include "conform_command.hpp"

#include <cstdio>
#include <filesystem>
#include <memory>

#include "sensornet/conform/conform_run.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/io/output_file.hpp"

namespace sensornet::launcher {
namespace {

struct ConformCommandOptions {
  std::string role;
  std::string junit_path;
  conform::ConformOptions run;
};

int runConform(ConformCommandOptions options) {
  if (options.role == "fusion-center") {
    options.run.role = conform::ConformRole::FusionCenter;
  } else if (options.role == "scheduler") {
    options.run.role = conform::ConformRole::Scheduler;
  } else if (options.role != "sensor") {
    throw InputError("sensornet conform", options.role,
                     "the role `sensor`, `fusion-center` or `scheduler`");
  }
  if (!options.junit_path.empty()) checkOutputFile(options.junit_path, "--junit");
  options.run.sensornet = std::filesystem::read_symlink("/proc/self/exe");
  const conform::ConformResult result = conform::conform(
      options.run, [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); });
  std::fputs(conform::ruleTable(result.rules).c_str(), stdout);
  std::printf("the run's files: %s\n", result.dir.c_str());
  if (!options.junit_path.empty()) {
    replaceFileAtomically(
        options.junit_path,
        conform::rulesJunit("sensornet conform " + options.role, result.rules, result.seconds));
  }
  return result.allPass() ? kExitOk : kExitFailure;
}

}  // namespace

Subcommand addConformCommand(CLI::App& app) {
  auto options = std::make_shared<ConformCommandOptions>();
  options->run.scenario = "scenarios/default.yaml";
  CLI::App* cmd = app.add_subcommand(
      "conform",
      "Check that your participant keeps the protocol (docs/wire-protocol.md): runs a launched "
      "run with your program in a role and checks what the run recorded rule by rule. A "
      "sensor (`sensornet launch --external-sensors J --record`): readiness before the first "
      "episode, the status period, measurement times, schedule versions, seq numbers and "
      "tallies, the arrival law (a time-rescaling test at a false-alarm rate of 0.001), "
      "nothing lost or refused, leaving on shutdown, the run's outcome; with --measures-truth, "
      "its z against the plant's truth and the NEES. A fusion center (`--external-fusion-center "
      "--reference-fusion`): a Report per episode, costs, brackets and counts equal to our "
      "exact CD-KF's on the same measurements, leaving, the outcome. A scheduler (an "
      "operator: `--drop-first-command-copy`, the coordinator leaves each command's first copy "
      "unanswered): commands in the operator's partition, ids of their own, written again "
      "every 2 s until the reply and not after it, accepted, leaving, the outcome. Prints a "
      "table (rule, ok/FAIL, evidence, the page's section); exit 0 only when every rule "
      "holds, 1 when one fails, 2 on bad input. Your command line may hold {run_id}, {domain_id} and {config} "
      "(a sensor's also {sensor} and {dim}); it runs with CYCLONEDDS_URI set to the run's "
      "configuration. Examples:\n"
      "  sensornet conform sensor --sensor 1 -- ./external_sensor --run-id {run_id} "
      "--domain-id {domain_id} --sensor {sensor} --measure truth\n"
      "  sensornet conform scheduler -- sensornet replan --run-id {run_id} --domain-id "
      "{domain_id} --surrogate info");
  cmd->add_option("ROLE", options->role,
                  "the role your program fills: sensor, fusion-center, scheduler")
      ->required();
  cmd->add_option("PROGRAM", options->run.program, "your participant's command line, after `--`")
      ->required();
  cmd->add_option("--sensor", options->run.sensor, "the sensor id your program speaks for")
      ->capture_default_str();
  cmd->add_option("--scenario", options->run.scenario, "the scenario of the run")
      ->capture_default_str();
  cmd->add_option("--episodes", options->run.episodes, "episodes of the run")
      ->check(integerRange(1, 100000))
      ->capture_default_str();
  cmd->add_option("--time-scale", options->run.time_scale, "emulated seconds per wall second")
      ->check(positiveNumber(1e4))
      ->capture_default_str();
  cmd->add_option("--seed", options->run.seed, "the run seed")->capture_default_str();
  cmd->add_flag("--measures-truth", options->run.measures_truth,
                "your program measures the plant's truth (a sensor through the world library) or "
                "estimates the state (a fusion center): check z against the truth and the NEES");
  cmd->add_option("--tolerance", options->run.tolerance,
                  "a fusion center's costs and brackets against ours, relative")
      ->check(positiveNumber(1.0))
      ->capture_default_str();
  cmd->add_option("--run-id", options->run.run_id,
                  "the run's id (default: conform- and 8 random hex digits)");
  cmd->add_option("--dir", options->run.dir,
                  "where the run's files go: logs, report, recording (default: a new folder "
                  "under the system's temporary folder)");
  cmd->add_option("--junit", options->junit_path, "also write the rules as JUnit XML");
  cmd->add_option("--launch-option", options->run.launch_args,
                  "an option passed to `sensornet launch` as is (repeat it)")
      ->allow_extra_args(false);
  return {cmd, [options] { return runConform(*options); }};
}

}  // namespace sensornet::launcher
