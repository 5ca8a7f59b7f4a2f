#include "plan_command.hpp"

#include <spdlog/spdlog.h>

#include <cstdio>
#include <limits>
#include <memory>
#include <string>

#include "sensornet/core/input_error.hpp"
#include "sensornet/io/output_path.hpp"
#include "sensornet/io/plan_request.hpp"
#include "sensornet/io/plan_summary.hpp"
#include "sensornet/io/scenario_file.hpp"
#include "sensornet/io/word_option.hpp"

namespace sensornet::coordinator {
namespace {

struct PlanOptions {
  std::string scenario_path;
  std::string out_path;
  PlanChoices choices;
  bool json = false;
};

// --out -: the schedule file's text goes to standard output, and nothing else does.
constexpr const char* kStandardOutput = "-";

int runPlan(const PlanOptions& options) {
  const bool to_stdout = options.out_path == kStandardOutput;
  if (to_stdout && options.json) {
    throw InputError("command line", "--json",
                     "no --json with --out - (the schedule file takes standard output; the "
                     "summary goes to standard error)");
  }
  const Scenario scenario = loadScenarioFile(options.scenario_path);
  // A folder the schedule cannot go in is bad input now, not after the solve.
  if (!to_stdout) makeParentFolders(options.out_path, "--out");
  const PlanChoices& choices = options.choices;
  PlanRequest request = planRequest(scenario, options.scenario_path, choices);
  request.progress = planProgressLog(choices.surrogate);
  const PlanResult plan = planSchedule(scenario, request);
  const PlanSummary summary{plan, choices.surrogate,
                            deliveredBracket(scenario, plan.schedule, plan.bracket),
                            choices.network_aware};
  writePlannedSchedule(options.out_path, plan.schedule, planRecord(summary));
  if (!solved(plan.status)) {
    spdlog::warn("plan: solver status '{}'; the best schedule found was written",
                 statusText(plan.status, plan.failure));
  }
  if (options.json) {
    printJson(planJsonLine(summary, options.out_path));
    return kExitOk;
  }
  // With --out - the summary goes to standard error: standard output holds the schedule only.
  std::fputs(planSummaryText(summary, scenario, options.scenario_path,
                             to_stdout ? "to standard output" : options.out_path)
                 .c_str(),
             to_stdout ? stderr : stdout);
  return kExitOk;
}

}  // namespace

Subcommand addPlanCommand(CLI::App& app) {
  auto options = std::make_shared<PlanOptions>();
  CLI::App* cmd = app.add_subcommand(
      "plan",
      "Compute the rate schedule (piecewise constant on the scenario's N intervals) that "
      "minimizes a surrogate of the expected CD-KF cost under the resource constraints "
      "C λ <= b, λ >= 0, write it as a schedule file, and report its bracket "
      "J(P_info) <= E[J] <= J(P_cov). Example:\n  coordinator plan --scenario "
      "scenarios/default.yaml --surrogate info --out plan.json --json");
  cmd->add_option("--scenario", options->scenario_path, "scenario file (YAML)")->required();
  wordOption<PlanSurrogate>(
      cmd->add_option("--surrogate", options->choices.surrogate,
                      "info: information-form surrogate (lower bound, the paper's Info-NLP); cov: "
                      "covariance-form surrogate (upper bound, Cov-NLP); uniform: the baseline, "
                      "no optimization; mc: the expected realized cost E[J] itself, by Monte Carlo "
                      "(objective = mean +- 95% half-width on fresh episodes; 55 s by default)"));
  cmd->add_option("--out", options->out_path,
                  "schedule file to write (JSON, written atomically; missing folders are made), "
                  "or - for standard output (then the summary goes to standard error)")
      ->required();
  cmd->add_option("--warm-start", options->choices.warm_start_path,
                  "schedule file to start the optimizer from (default: the uniform schedule)");
  cmd->add_option("--exclude", options->choices.excluded,
                  "sensor indices (0-based) taken out of service: rate 0 throughout")
      ->delimiter(',');
  wordOption<PlanMethod>(cmd->add_option("--method", options->choices.method,
                                         "optimizer: pqn (projected quasi-Newton, default) or "
                                         "ipopt (interior point, L-BFGS Hessian)"));
  cmd->add_option("--tolerance", options->choices.tolerance,
                  "stop when the scale-free projected-gradient residual is below this")
      ->capture_default_str()
      ->check(positiveNumber());
  cmd->add_option("--max-iterations", options->choices.max_iterations, "iteration limit")
      ->capture_default_str()
      ->check(integerRange(0, std::numeric_limits<int>::max()));
  CLI::Option* max_seconds =
      cmd->add_option("--max-seconds", options->choices.max_seconds,
                      "wall-time limit of the solve (mc: of the whole plan, default 55)")
          ->capture_default_str()
          ->check(positiveNumber());
  cmd->add_flag("--network-aware", options->choices.network_aware,
                "plan for the rates the scenario's network: section delivers (loss thins them, "
                "outages of every episode zero them) while C λ <= b binds the planned rates; "
                "refused without a network: section");
  cmd->add_flag("--json", options->json,
                "print {\"surrogate\", \"objective\", \"bracket\", \"delivered_bracket\" "
                "(of what the network delivers in episode 0), \"network_aware\", \"iterations\", "
                "\"substeps\" (RK4 steps per interval of the planner's transcription), "
                "\"solve_seconds\", \"status\", \"kkt_residual\"} as one JSON line");
  return {cmd, [options, max_seconds] {
            options->choices.max_seconds_given = max_seconds->count() > 0;
            return runPlan(*options);
          }};
}

}  // namespace sensornet::coordinator
