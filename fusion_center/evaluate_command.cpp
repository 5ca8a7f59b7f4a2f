#include "evaluate_command.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <memory>
#include <optional>
#include <string>

#include "sensornet/core/arrival_mode.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/core/monte_carlo.hpp"
#include "sensornet/core/planner.hpp"
#include "sensornet/core/student_t.hpp"
#include "sensornet/core/surrogate.hpp"
#include "sensornet/emulator/closed_loop.hpp"
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

// The closed loop's surrogate: --surrogate, else the schedule file's "surrogate" when it is
// one the closed loop plans with, else cov (the run's default).
PlanSurrogate closedLoopSurrogate(const EvaluateOptions& options) {
  if (!options.surrogate.empty()) return *lookUpWord<PlanSurrogate>(options.surrogate);
  if (!options.schedule_path.empty()) {
    const nlohmann::json file =
        nlohmann::json::parse(readTextFile(options.schedule_path, "schedule"), nullptr, false);
    if (file.is_object() && file.contains("surrogate") && file["surrogate"].is_string()) {
      const auto named = lookUpWord<PlanSurrogate>(file["surrogate"].get<std::string>());
      if (named == PlanSurrogate::Information || named == PlanSurrogate::Covariance) return *named;
    }
  }
  return PlanSurrogate::Covariance;
}

int runClosedLoop(const EvaluateOptions& options, const Scenario& scenario,
                  const RateSchedule& schedule, const CostBracket& bracket) {
  emulator::ClosedLoopOptions loop;
  loop.replan_every_s = options.replan_every;
  loop.surrogate = closedLoopSurrogate(options);
  if (loop.surrogate != PlanSurrogate::Information && loop.surrogate != PlanSurrogate::Covariance) {
    throw InputError("--surrogate", "", "info or cov for --replan-every");
  }
  loop.replanner.switch_margin_s = options.switch_margin;
  loop.replanner.time_scale = options.time_scale;
  loop.runs = options.runs;
  loop.seed = options.seed;
  loop.threads = options.threads;
  int last_decile = 0;
  loop.progress = [&last_decile](int done, int total) {
    const int decile = 10 * done / total;
    if (decile > last_decile) {
      last_decile = decile;
      spdlog::info("closed loop: {}/{} episodes", done, total);
    }
  };
  const auto start = std::chrono::steady_clock::now();
  const emulator::ClosedLoopResult closed = emulator::simulateClosedLoop(scenario, schedule, loop);
  const std::vector<double> open =
      emulator::openLoopCosts(scenario, schedule, options.runs, options.seed, options.threads);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!options.costs_path.empty()) {
    std::ofstream out(options.costs_path);
    out.precision(17);
    for (const double c : closed.episode_costs) out << c << "\n";
    out.close();
    if (!out) throw InputError(options.costs_path, "", "a writable file for --costs");
  }
  double open_mean = 0.0;
  for (const double c : open) open_mean += c / static_cast<double>(open.size());
  const SampleMean gain = pairedDifference(closed.episode_costs, open);
  const std::string surrogate(wordOf(loop.surrogate));
  const double margin = options.switch_margin * options.time_scale;
  if (options.json) {
    printJson({{"closed_loop",
                {{"replan_every", options.replan_every},
                 {"surrogate", surrogate},
                 {"switch_margin_emulated", margin},
                 {"mean", closed.mean},
                 {"std", closed.std_dev},
                 {"ci95", closed.ci95},
                 {"runs", closed.runs},
                 {"tails_per_episode", closed.tails_mean},
                 {"refused", closed.refused},
                 {"arrivals", closed.arrivals_mean}}},
               {"open_loop", {{"mean", open_mean}}},
               {"closed_minus_open", {{"mean", gain.mean}, {"ci95", gain.ci95}}},
               {"bracket", {{"info", bracket.info}, {"cov", bracket.cov}}},
               {"schedule", options.schedule_path.empty() ? "uniform" : options.schedule_path},
               {"seed", options.seed},
               {"seconds", seconds}});
    return kExitOk;
  }
  std::printf("scenario  %s (n = %d states, M = %d sensors, T = %g s, N = %d)\n",
              options.scenario_path.c_str(), scenario.stateDim(), scenario.sensorCount(),
              scenario.horizon_s, scenario.intervals);
  std::printf("open-loop plan  %s (bracket [%.6g, %.6g] of the plan alone)\n",
              options.schedule_path.empty() ? "uniform" : options.schedule_path.c_str(),
              bracket.info, bracket.cov);
  std::printf("closed loop  re-plan with %s every %g s, each tail from %g s later; %.2f tails "
              "per episode, %lld refused\n",
              surrogate.c_str(), options.replan_every, margin, closed.tails_mean, closed.refused);
  std::printf("closed loop  mean %.6g ± %.3g (95%%), std %.4g, %d episodes in %.2f s\n",
              closed.mean, closed.ci95, closed.std_dev, closed.runs, seconds);
  std::printf("open loop    mean %.6g on the same arrivals (time-changed unit-rate points)\n",
              open_mean);
  std::printf("closed - open  %+.6g ± %.3g (95%%, paired): %s\n", gain.mean, gain.ci95,
              gain.mean + gain.ci95 < 0.0   ? "feedback pays"
              : gain.mean - gain.ci95 > 0.0 ? "feedback costs"
                                            : "no difference at this sample size");
  return kExitOk;
}

// With timetable arrivals: the deterministic cost of the timetable beside the Poisson mean of
// the same schedule (which the bracket is about).
nlohmann::json timetableJson(const MonteCarloResult& timetable, const MonteCarloResult& poisson,
                             bool simulate_plant) {
  nlohmann::json doc = {{"cost", timetable.mean},
                        {"std", timetable.std_dev},
                        {"arrivals", timetable.arrivals_mean},
                        {"minus_poisson_mean", timetable.mean - poisson.mean},
                        {"poisson_ci95", poisson.ci95}};
  doc["nees"] = simulate_plant ? nlohmann::json(timetable.nees_mean) : nlohmann::json(nullptr);
  return doc;
}

void printTimetable(const MonteCarloResult& timetable, const MonteCarloResult& poisson,
                    bool simulate_plant) {
  std::printf("timetable  J = %.6g (std over episodes %.3g), %.0f arrivals per episode\n",
              timetable.mean, timetable.std_dev, timetable.arrivals_mean);
  std::printf("           minus the Poisson mean: %.6g (Poisson 95%% half-width %.3g)\n",
              timetable.mean - poisson.mean, poisson.ci95);
  if (simulate_plant) std::printf("           mean NEES at T %.4g\n", timetable.nees_mean);
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
  int last_decile = 0;
  mc_options.progress = [&last_decile](int done, int total) {
    const int decile = 10 * done / total;
    if (decile > last_decile) {
      last_decile = decile;
      spdlog::info("monte carlo: {}/{} episodes", done, total);
    }
  };
  const auto start = std::chrono::steady_clock::now();
  const MonteCarloResult mc = evaluateSchedule(scenario, schedule, mc_options);
  std::optional<MonteCarloResult> timetable;
  const ArrivalMode mode =
      options.arrivals.empty() ? scenario.arrivals
                               : parseArrivalMode(options.arrivals, "--arrivals", "arrivals");
  if (mode == ArrivalMode::Timetable) {
    mc_options.arrivals = ArrivalMode::Timetable;
    timetable = evaluateSchedule(scenario, schedule, mc_options);
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const bool meets_bracket = mc.mean - mc.ci95 <= bracket.cov && mc.mean + mc.ci95 >= bracket.info;

  if (options.json) {
    nlohmann::json doc = {
        {"bracket", {{"info", bracket.info}, {"cov", bracket.cov}}},
        {"mc", {{"mean", mc.mean}, {"std", mc.std_dev}, {"ci95", mc.ci95}, {"runs", mc.runs}}},
        {"meets_bracket", meets_bracket},
        {"schedule", options.schedule_path.empty() ? "uniform" : options.schedule_path},
        {"arrivals", arrivalModeName(mode)},
        {"seed", options.seed},
        {"seconds", seconds}};
    if (mc_options.simulate_plant) {
      doc["nees"] = mc.nees_mean;
      doc["squared_error"] = mc.squared_error_mean;
    } else {
      doc["nees"] = nullptr;
    }
    doc["timetable"] = timetable ? timetableJson(*timetable, mc, mc_options.simulate_plant)
                                 : nlohmann::json(nullptr);
    printJson(doc);
    return kExitOk;
  }
  std::printf("scenario  %s (n = %d states, M = %d sensors, T = %g s, N = %d)\n",
              options.scenario_path.c_str(), scenario.stateDim(), scenario.sensorCount(),
              scenario.horizon_s, scenario.intervals);
  std::printf("schedule  %s\n",
              options.schedule_path.empty() ? "uniform" : options.schedule_path.c_str());
  std::printf("bracket   J(P_info) = %.6g <= E[J] <= J(P_cov) = %.6g\n", bracket.info,
              bracket.cov);
  std::printf("arrivals  %s\n", std::string(arrivalModeName(mode)).c_str());
  std::printf("monte carlo  mean %.6g ± %.3g (95%%), std %.4g, %d episodes in %.2f s\n", mc.mean,
              mc.ci95, mc.std_dev, mc.runs, seconds);
  std::printf("             the 95%% interval %s the bracket\n",
              meets_bracket ? "meets" : "DOES NOT meet");
  if (mc_options.simulate_plant) {
    std::printf("simulated plant  mean NEES at T %.4g (ideal %d), mean e'W_T e at T %.6g\n",
                mc.nees_mean, scenario.stateDim(), mc.squared_error_mean);
  }
  if (timetable) printTimetable(*timetable, mc, mc_options.simulate_plant);
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
