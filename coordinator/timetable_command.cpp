#include "timetable_command.hpp"

#include <memory>
#include <spdlog/spdlog.h>

#include "sensornet/core/brownian_instants.hpp"
#include "sensornet/io/command_line.hpp"

namespace sensornet::coordinator {
namespace {

struct TimetableOptions {
  BrownianProblem problem;
  bool json = false;
};

int runTimetable(const TimetableOptions& options) {
  validateBrownianProblem(options.problem, "command line");
  const BrownianSchedule schedule = optimalInstants(options.problem);
  const auto n = options.problem.variances.size();
  if (options.json) {
    nlohmann::json doc = {{"instants", schedule.instants},
                          {"cost", schedule.cost},
                          {"regular_cost", schedule.regular_cost}};
    if (n <= 2) doc["regime"] = schedule.regime;
    printJson(doc);
    return kExitOk;
  }
  std::printf("optimal instants for %zu measurement(s) over T = %g:\n", n,
              options.problem.horizon_s);
  for (std::size_t k = 0; k < n; ++k) {
    std::printf("  t_%zu = %.9g  (noise variance %g)\n", k + 1, schedule.instants[k],
                options.problem.variances[k]);
  }
  std::printf("cost (eq. 12): %.9g\nregular instants kT/(n+1): %.9g  (gain %.2f%%)\n",
              schedule.cost, schedule.regular_cost,
              100.0 * (schedule.regular_cost - schedule.cost) / schedule.regular_cost);
  if (n <= 2) std::printf("regime: %d\n", schedule.regime);
  return kExitOk;
}

}  // namespace

Subcommand addTimetableCommand(CLI::App& app) {
  auto options = std::make_shared<TimetableOptions>();
  CLI::App* cmd = app.add_subcommand(
      "timetable",
      "Optimal instants t_1 <= ... <= t_n in [0, T] for n noisy measurements of a scalar "
      "Brownian motion, minimizing the mean estimation variance (eq. 12 of the Brownian "
      "paper). Example:\n  coordinator timetable --sigma2 1 --horizon 1 --v0 0.5 "
      "--variances 1,2,3 --json");
  cmd->add_option("--sigma2", options->problem.sigma2,
                  "variance rate σ² of the Brownian motion (> 0)")
      ->required();
  cmd->add_option("--horizon", options->problem.horizon_s, "duration T in seconds (> 0)")
      ->required();
  cmd->add_option("--v0", options->problem.v0, "variance of the prior on θ(0) (>= 0)")
      ->required();
  cmd->add_option("--variances", options->problem.variances,
                  "noise variances v_1,...,v_n of the measurements, in the order they are taken")
      ->required()
      ->delimiter(',');
  cmd->add_flag("--json", options->json,
                "print {\"instants\", \"cost\", \"regular_cost\", \"regime\"} as JSON");
  return {cmd, [options] { return runTimetable(*options); }};
}

}  // namespace sensornet::coordinator
