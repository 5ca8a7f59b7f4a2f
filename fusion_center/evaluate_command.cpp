#include "evaluate_command.hpp"

#include <memory>
#include <optional>
#include <string>

#include "sensornet/core/input_error.hpp"
#include "sensornet/core/surrogate.hpp"
#include "sensornet/evaluation/evaluation_summary.hpp"
#include "sensornet/evaluation/schedule_evaluation.hpp"
#include "sensornet/io/scenario_file.hpp"
#include "sensornet/io/word_option.hpp"

namespace sensornet::fusion_center {
namespace {

struct EvaluateOptions {
  std::string scenario_path;
  std::string schedule_path;  // empty: the uniform schedule
  int runs = 1000;
  std::uint64_t seed = 1;
  int threads = 0;
  bool no_plant = false;
  bool json = false;
  std::string arrivals;  // empty: the scenario file's `arrivals:` (Poisson when absent)
  double replan_every = 0.0;  // > 0: the closed loop of --replan-every
  std::string surrogate;      // closed loop: info or cov (empty: the schedule file's, else cov)
  double switch_margin = 0.3;
  double time_scale = 1.0;
  std::string costs_path;  // closed loop: every episode's cost, one per line
};

// The schedule evaluated, as the summaries name it.
std::string scheduleName(const EvaluateOptions& options) {
  return options.schedule_path.empty() ? "uniform" : options.schedule_path;
}

int runClosedLoop(const EvaluateOptions& options, const Scenario& scenario,
                  const RateSchedule& schedule, const CostBracket& bracket) {
  evaluation::ClosedLoopOptions loop;
  loop.replan_every_s = options.replan_every;
  loop.surrogate = evaluation::closedLoopSurrogate(
      options.surrogate,
      options.schedule_path.empty() ? "" : readTextFile(options.schedule_path, "schedule"));
  loop.replanner.switch_margin_s = options.switch_margin;
  loop.replanner.time_scale = options.time_scale;
  loop.runs = options.runs;
  loop.seed = options.seed;
  loop.threads = options.threads;
  loop.progress = evaluation::decileProgress("closed loop");
  const evaluation::ClosedLoopRun run = evaluation::runClosedLoop(scenario, schedule, loop);
  if (!options.costs_path.empty()) {
    evaluation::writeEpisodeCosts(options.costs_path, run.closed.episode_costs);
  }
  const evaluation::ClosedLoopEvaluation e{scenario,
                                           options.scenario_path,
                                           scheduleName(options),
                                           bracket,
                                           run.closed,
                                           run.open_mean,
                                           run.gain,
                                           loop.surrogate,
                                           options.replan_every,
                                           options.switch_margin * options.time_scale,
                                           options.seed,
                                           run.seconds};
  if (options.json) {
    printJson(evaluation::closedLoopJson(e));
  } else {
    std::fputs(evaluation::closedLoopText(e).c_str(), stdout);
  }
  return kExitOk;
}

int runEvaluate(const EvaluateOptions& options) {
  const Scenario scenario = loadScenarioFile(options.scenario_path);
  const RateSchedule schedule = options.schedule_path.empty()
                                    ? uniformSchedule(scenario)
                                    : loadScheduleFile(options.schedule_path, scenario);
  const CostBracket bracket = computeBracket(scenario, schedule);
  if (options.replan_every > 0.0) return runClosedLoop(options, scenario, schedule, bracket);

  MonteCarloOptions mc_options;
  mc_options.runs = options.runs;
  mc_options.seed = options.seed;
  mc_options.threads = options.threads;
  mc_options.simulate_plant = !options.no_plant;
  mc_options.progress = evaluation::decileProgress("monte carlo");
  const ArrivalMode mode =
      options.arrivals.empty() ? scenario.arrivals
                               : parseWord<ArrivalMode>(options.arrivals, "--arrivals", "arrivals");
  const evaluation::OpenLoopRun run = evaluation::runOpenLoop(scenario, schedule, mc_options, mode);
  const evaluation::OpenLoopEvaluation e{scenario,
                                       options.scenario_path,
                                       scheduleName(options),
                                       bracket,
                                       run.mc,
                                       run.timetable ? &*run.timetable : nullptr,
                                       mode,
                                       mc_options.simulate_plant,
                                       options.seed,
                                       run.seconds};
  if (options.json) {
    printJson(evaluation::evaluationJson(e));
  } else {
    std::fputs(evaluation::evaluationText(e).c_str(), stdout);
  }
  return kExitOk;
}

}  // namespace

Subcommand addEvaluateCommand(CLI::App& app) {
  auto options = std::make_shared<EvaluateOptions>();
  CLI::App* cmd = app.add_subcommand(
      "evaluate",
      "Evaluate a rate schedule offline: the two-sided surrogate bracket "
      "J(P_info) <= E[J(P)] <= J(P_cov) and a Monte Carlo estimate of E[J(P)] with the exact "
      "CD-KF and Poisson arrivals. Example:\n  fusion_center evaluate --scenario "
      "scenarios/default.yaml --runs 2000 --seed 7 --json");
  cmd->add_option("--scenario", options->scenario_path, "scenario file (YAML)")->required();
  cmd->add_option("--schedule", options->schedule_path,
                  "schedule file (JSON: horizon, intervals, rates); default: the uniform "
                  "schedule (the largest equal constant rate meeting every constraint)");
  cmd->add_option("--runs", options->runs, "Monte Carlo episodes")
      ->capture_default_str()
      ->check(integerRange(2, 100'000'000));
  cmd->add_option("--seed", options->seed, "run seed (the result depends only on it)")
      ->capture_default_str();
  cmd->add_option("--threads", options->threads, "worker threads (0: one per core)")
      ->capture_default_str()
      ->check(integerRange(0, 1024));
  wordOption(cmd->add_option("--arrivals", options->arrivals,
                             "timetable: deterministic instants where the integrated rate is "
                             "k - 1/2; default: the scenario's `arrivals:`. The Monte Carlo mean "
                             "is always that of Poisson arrivals; with timetable the "
                             "timetable's cost is printed beside it"),
             wordTexts<ArrivalMode>());
  cmd->add_option("--replan-every", options->replan_every,
                  "simulate the closed loop of `sensornet launch --replan-every DT` instead: the "
                  "schedule is every episode's open-loop plan, and at each multiple of DT "
                  "emulated seconds the rest of the episode is re-planned from the filter's "
                  "covariance (the coordinator's planner and switch rule; planning takes no "
                  "time here). Prints the closed loop's mean cost and its paired difference to "
                  "the open-loop plan on the same arrivals")
      ->check(positiveNumber(1e9));
  wordOption(cmd->add_option("--surrogate", options->surrogate,
                             "with --replan-every: the surrogate the tails are planned with "
                             "(default: the schedule file's \"surrogate\" when info or cov, "
                             "else cov)"),
             {"info", "cov"});
  cmd->add_option("--switch-margin", options->switch_margin,
                  "with --replan-every: the coordinator's --switch-margin (wall seconds)")
      ->capture_default_str()
      ->check(positiveNumber(1e6));
  cmd->add_option("--time-scale", options->time_scale,
                  "with --replan-every: the run's --time-scale (the margin in emulated seconds "
                  "is the two multiplied)")
      ->capture_default_str()
      ->check(positiveNumber(1e6));
  cmd->add_option("--costs", options->costs_path,
                  "with --replan-every: write every episode's closed-loop cost J(P) to FILE, "
                  "one per line, in episode order");
  cmd->add_flag("--no-plant", options->no_plant,
                "skip simulating the true state (faster; no NEES or squared error)");
  cmd->add_flag("--json", options->json,
                "print {\"bracket\", \"mc\", \"nees\", \"timetable\", ...} as one JSON line");
  return {cmd, [options] { return runEvaluate(*options); }};
}

}  // namespace sensornet::fusion_center
