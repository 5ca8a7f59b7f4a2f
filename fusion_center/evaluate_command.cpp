#include "evaluate_command.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <memory>
#include <optional>
#include <string>

#include "sensornet/core/arrival_mode.hpp"
#include "sensornet/core/monte_carlo.hpp"
#include "sensornet/core/surrogate.hpp"
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
};

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
  cmd->add_flag("--no-plant", options->no_plant,
                "skip simulating the true state (faster; no NEES or squared error)");
  cmd->add_flag("--json", options->json,
                "print {\"bracket\", \"mc\", \"nees\", \"timetable\", ...} as one JSON line");
  return {cmd, [options] { return runEvaluate(*options); }};
}

}  // namespace sensornet::fusion_center
